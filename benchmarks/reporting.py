"""What the benchmark modules share: single-threaded OpenCV and the summary they print.

pytest-benchmark's table gives each timing alone; the ratios a benchmark exists for (ours
against a reference or a peer in the same run) are printed after the module's last test
with :func:`write_report`. Imported as ``reporting`` (pytest puts this folder on the path).
"""
from __future__ import annotations

from contextlib import contextmanager
from typing import Iterable, Iterator

import cv2


@contextmanager
def single_cv2_thread() -> Iterator[None]:
    """OpenCV on one thread inside the block (every timing single-threaded), restored after."""
    previous = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        yield
    finally:
        cv2.setNumThreads(previous)


def write_report(request, title: str, lines: Iterable[str]) -> None:
    """Print ``title`` and ``lines`` on the terminal, past pytest's output capture (a
    module fixture's teardown is captured otherwise); nothing when there is nothing to say."""
    lines = list(lines)
    reporter = request.config.pluginmanager.get_plugin("terminalreporter")
    capture = request.config.pluginmanager.get_plugin("capturemanager")
    if reporter is None or capture is None or not lines:
        return
    with capture.global_and_fixture_disabled():
        reporter.write_line(f"\n{title}")
        for line in lines:
            reporter.write_line(line)
