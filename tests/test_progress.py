"""Progress bars (issue 22): tqdm on a terminal, whole lines at most one per few seconds anywhere else."""

import io

from _shared.progress import PLAIN_INTERVAL_S, progress_bar


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_off_a_terminal_a_bar_writes_whole_lines_only_at_its_start_and_end():
    log = io.StringIO()
    for _ in progress_bar(range(20000), desc="collect", unit="tap", file=log):
        pass
    text = log.getvalue()
    lines = text.splitlines()
    assert "\r" not in text and text.endswith("\n")
    # A loop far shorter than the interval: the first line and the final one, nothing between.
    assert len(lines) == 2 and lines[0].startswith("collect:   0%") and "20000/20000" in lines[-1]


def test_off_a_terminal_the_interval_is_a_few_seconds_and_a_bar_left_off_still_ends_with_a_line():
    log = io.StringIO()
    with progress_bar(total=5, desc="fixations", file=log, leave=False, mininterval=0.1) as bar:
        assert bar.mininterval >= PLAIN_INTERVAL_S >= 2
        bar.update(5)
    assert log.getvalue().splitlines()[-1].startswith("fixations: 100%")


def test_on_a_terminal_the_bar_is_tqdm_as_usual():
    screen = _Terminal()
    for _ in progress_bar(range(100), desc="replay", file=screen):
        pass
    assert "\r" in screen.getvalue()                                    # redrawn in place


def test_a_disabled_bar_writes_nothing():
    log = io.StringIO()
    for _ in progress_bar(range(10), file=log, disable=True):
        pass
    assert log.getvalue() == ""
