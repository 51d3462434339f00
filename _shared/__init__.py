"""The one shared leaf of the tree: helpers every package may import, importing none of them.

- `_shared.files`: atomic file writing, honest write errors, outputs never over inputs, HDF5 in memory;
- `_shared.toml`: one TOML reader with errors that name the file and what is wrong with it;
- `_shared.ranges`: one range check, whose text every refusal of an out-of-range number uses;
- `_shared.mapping`: independent pieces of work run in turn, or through a map-like callable (a cluster's).
- `_shared.progress`: every progress bar (tqdm on a terminal, a plain line every few seconds elsewhere).

So the logic lives once and no package reaches into another for it (`tests/test_layout.py` keeps
it a leaf). It imports only the standard library (h5py and tqdm inside the helpers that need them).
"""

from _shared.files import (atomic_path, cut_short, discard_temporary, fsync_path, hdf5_in_memory, output_temporary, publish,
                           refuse_overwriting_inputs, remove_stale_temporaries, stream_target, temporary_name,
                           write_error)
from _shared.mapping import map_pieces
from _shared.ranges import outside_range
from _shared.toml import parse_toml

__all__ = ["atomic_path", "refuse_overwriting_inputs", "write_error", "fsync_path", "temporary_name", "cut_short",
           "remove_stale_temporaries", "hdf5_in_memory", "stream_target", "output_temporary", "publish", "discard_temporary",
           "outside_range", "parse_toml", "map_pieces"]
