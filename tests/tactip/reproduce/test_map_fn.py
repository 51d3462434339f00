"""Paper 000 hands its mapper to the class counts it maps.

tests/tactip/test_cluster.py runs `acuity_table` on a Dask cluster, and papers 001 and 003 through
`reproduce(..., map_fn=...)` end to end; this checks, without a second quick reproduction, that
`reproduce("000", map_fn=...)` passes its mapper down to `acuity_table` (both sensors' tables go through
the same `p000._table`; the first, the fingertip's, is checked).
"""
import pytest

import tactip.reproduce.acuity as acuity
from tactip.reproduce import reproduce


class _Handed(Exception):
    pass


def test_paper_000_maps_its_class_counts_with_the_given_map_fn(monkeypatch):
    seen = []

    def recording_acuity_table(train, test, *, map_fn=None, **options):
        seen.append((map_fn, tuple(options["class_counts"])))
        raise _Handed

    def mapper(function, pieces):
        return [function(piece) for piece in pieces]

    monkeypatch.setattr(acuity, "acuity_table", recording_acuity_table)
    with pytest.raises(_Handed):
        reproduce("000", quick=True, seed=0, map_fn=mapper)
    assert len(seen) == 1 and seen[0][0] is mapper
    assert len(seen[0][1]) >= 2                      # several class counts to map
