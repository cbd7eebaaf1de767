"""The XDMF file beside a results file, appended to frame by frame at constant cost.

``<stem>.xdmf`` holds one temporal collection per body (:mod:`pdfem.output.xdmf_grids`).
Each temporal collection is followed on disk by a run of spaces (a reserve); a new frame's
grid is written over the start of each collection's reserve, in place, one ``write`` per
collection, so the file is well-formed XML before and after each write. When a reserve runs
out the whole file is written again (atomically, through a temporary file and
``os.replace``) with every reserve as large as its collection's text so far: the rewrites
come at geometrically spaced frames, so the cost per frame is O(1) amortized and O(1) outside
the rewrite frames (measured in ``benchmarks/output_frames.py``).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from typing import Protocol

HEAD = '<?xml version="1.0" encoding="utf-8"?>\n<Xdmf Version="3.0">\n  <Domain>\n'
TAIL = "  </Domain>\n</Xdmf>\n"
CLOSE = "\n    </Grid>\n"
MIN_RESERVE = 4096
"""Bytes of spaces kept after each temporal collection at least (see the module docstring)."""

MAX_PLANNED_RESERVE = 64 * 1024 * 1024
"""Most bytes reserved per collection for the frames a run expects (``expected_frames``)."""


class Collection(Protocol):
    """A temporal collection of the file (:class:`pdfem.output.xdmf_grids.BodyGrid`)."""

    def head(self) -> str:
        """The collection's opening tag."""
        ...

    def frame_xml(self, index: int, time: float) -> str:
        """The collection's grid of frame ``index`` at ``time`` (s)."""
        ...


class XdmfFile:
    """The XDMF file of a results file, appended to frame by frame at constant cost.

    Parameters
    ----------
    path
        The ``.xdmf`` file (written when the first frame is added).
    expected_frames
        Frames the run expects to write (0: unknown). The first write reserves room for them
        (up to ``MAX_PLANNED_RESERVE`` bytes per collection), so that a run that writes no
        more frames than it expected never rewrites the file after its first frame.

    Notes
    -----
    Only the frame times are kept in memory; a rewrite makes every frame's text again. Set
    ``grids`` (the collections, in file order) before the first frame.
    """

    def __init__(self, path: Path, expected_frames: int = 0) -> None:
        self.path = Path(path)
        self.expected_frames = int(expected_frames)
        self.grids: list[Collection] = []
        self.times: list[float] = []
        self.rewrites = 0
        self._free: list[int] = []   # bytes of reserve left after each collection
        self._at: list[int] = []     # file offset where each collection's next frame goes

    def add_frame(self, time: float) -> None:
        """Add the next frame (time ``time``, s) of every grid to the file."""
        index = len(self.times)
        self.times.append(float(time))
        texts = [g.frame_xml(index, time).encode() for g in self.grids]
        if not self._at or any(len(t) > free for t, free in zip(texts, self._free)):
            self.rewrite()
            return
        fd = os.open(self.path, os.O_WRONLY)
        try:
            for k, text in enumerate(texts):
                os.pwrite(fd, text, self._at[k])
                self._at[k] += len(text)
                self._free[k] -= len(text)
        finally:
            os.close(fd)

    def set_times(self, times: Iterable[float]) -> None:
        """Replace the frames by those at ``times`` (s) (a restart) and write the file again."""
        self.times = [float(t) for t in times]
        self.rewrite()

    def rewrite(self) -> None:
        """Write the whole file, atomically, each reserve as large as its collection's text."""
        out = [HEAD.encode()]
        at, free = [], []
        pos = len(out[0])
        for g in (self.grids if self.times else []):
            head = g.head().encode()
            body = "".join(g.frame_xml(i, t) for i, t in enumerate(self.times)).encode()
            # room for the frames still expected, each as long as the last one plus the
            # longest difference a time value (repr) makes
            planned = ((len(g.frame_xml(0, self.times[-1])) + 32)
                       * (self.expected_frames - len(self.times)))
            reserve = max(MIN_RESERVE, len(head) + len(body),
                          min(planned, MAX_PLANNED_RESERVE))
            out += [head, body, b" " * reserve, CLOSE.encode()]
            at.append(pos + len(head) + len(body))
            free.append(reserve)
            pos += len(head) + len(body) + reserve + len(CLOSE)
        out.append(TAIL.encode())
        tmp = self.path.with_name(self.path.name + ".tmp")
        tmp.write_bytes(b"".join(out))
        os.replace(tmp, self.path)
        self._at, self._free = at, free
        self.rewrites += 1
