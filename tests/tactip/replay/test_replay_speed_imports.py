"""Replay without a progress bar does not import tqdm (a one-off ~0.03-0.06 s of a process's first replay)."""

import subprocess
import sys
import textwrap


def test_tracking_without_progress_imports_no_tqdm():
    code = textwrap.dedent("""
        import sys
        from tactip.errors import SourceError
        from tactip.pipeline import track_pins
        for progress in (False, lambda frames: None):
            try:
                track_pins(iter([]), start=lambda image: None, rest_frame=0, progress=progress)
            except SourceError:
                pass
        print("tqdm" in sys.modules)
    """)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "False", done.stderr
