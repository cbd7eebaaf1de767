"""Stopping a run on a signal: finish the coupling step, write a checkpoint and a last frame.

A batch scheduler ends a job at its time limit with SIGTERM and, a grace period later
(Slurm's ``KillWait``, 30 s by default), SIGKILL; it can also send a signal ahead of the limit
(Slurm: ``--signal=TERM@120``, docs/cluster.md). A user stops a run with Ctrl-C (SIGINT).
While :func:`stop_signals` is active, SIGTERM, SIGUSR1 and a first SIGINT only set the flag
of a :class:`StopRequest`; the time loop (:class:`pdfem.run.loop.Checkpoints`) reads it after
every coupling step, every rank agrees on it in the small collective the loop makes each step
anyway (a signal may reach only some ranks), and the run stops at that step with a checkpoint
and a last frame: exit status 4 (:data:`pdfem.errors.EXIT_STOPPED`), restartable with
``pdfem run CASE --out DIR --restart DIR/checkpoint.h5``. A second SIGINT stops at once
(``KeyboardInterrupt``; the results written so far stay readable, exit 1).

Only the command line installs the handlers (:mod:`pdfem.cli.run`), for the duration of the
run, and puts the previous ones back afterwards; nothing is installed at import.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

STOP_SIGNALS = (signal.SIGTERM, signal.SIGUSR1, signal.SIGINT)
"""The signals that stop a run at the end of its coupling step."""


class StopRequest:
    """The stop flag a signal handler sets and the time loop reads.

    Attributes
    ----------
    signal
        The number of the first stop signal received, 0 while none was.
    """

    def __init__(self) -> None:
        self.signal = 0

    def handle(self, signum: int, frame=None) -> None:
        """The signal handler: remember the first stop signal; a second SIGINT stops at once.

        Raises
        ------
        KeyboardInterrupt
            On SIGINT after a first SIGINT.
        """
        if signum == signal.SIGINT and self.signal == signal.SIGINT:
            raise KeyboardInterrupt
        if not self.signal:
            self.signal = int(signum)

    @property
    def name(self) -> str:
        """The signal's name (``"SIGTERM"``), or ``""`` while none was received."""
        return signal.Signals(self.signal).name if self.signal else ""


@contextmanager
def stop_signals() -> Iterator[StopRequest]:
    """Route SIGTERM, SIGUSR1 and SIGINT to a new :class:`StopRequest` while the block runs,
    then restore the previous handlers. Outside the main thread (where Python cannot install
    handlers) the request is given but never set.

    Yields
    ------
    StopRequest
        The flag to hand to :func:`pdfem.run.driver.run_case`.
    """
    stop = StopRequest()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return
    previous = {s: signal.signal(s, stop.handle) for s in STOP_SIGNALS}
    try:
        yield stop
    finally:
        for s, handler in previous.items():  # None: a handler not installed from Python
            signal.signal(s, signal.SIG_DFL if handler is None else handler)
