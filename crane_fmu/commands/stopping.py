"""Ctrl-C and SIGTERM as a run's end, not a crash: the signal is noted, and the run stops at its next
communication point (or block of points), outside any FMU's code.

Raising KeyboardInterrupt from the handler, Python's default, lands wherever the main thread is, and with
the Python FMUs that is inside an FMU's Python code: the FMU returns an error, and the run is reported as
that FMU's failure. SIGTERM (what CI, systemd and docker send) ends the process with no word by default.
"""

import signal


class Stopped(BaseException):
    """The run was stopped by the signal ``signum`` (a BaseException, as KeyboardInterrupt: no ``except
    Exception`` takes it)."""

    def __init__(self, signum):
        self.signum = signum
        super().__init__(signal.Signals(signum).name)


class StopOnSignal:
    """An observer of a run that raises :class:`Stopped` at the first observation after SIGINT, SIGTERM or SIGHUP;
    as a context manager it installs the handlers (and restores the previous ones). A second SIGINT interrupts
    at once (KeyboardInterrupt)."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM, *filter(None, [getattr(signal, "SIGHUP", None)]))  # HUP: the terminal

    def __init__(self):
        self.signum, self._previous = None, {}

    def __enter__(self):
        self._previous = {s: signal.signal(s, self._note) for s in self.SIGNALS}
        return self

    def __exit__(self, *exc):
        for s, handler in self._previous.items():
            signal.signal(s, handler)
        return False

    def _note(self, signum, frame):
        if self.signum is not None and signum == signal.SIGINT:
            raise KeyboardInterrupt
        self.signum = signum

    def check(self):
        """Raise :class:`Stopped` if a signal came."""
        if self.signum is not None:
            raise Stopped(self.signum)

    # --- as an observer (after the recorder, so that the rows it is told of are kept) ---

    def start(self, names):
        self.check()

    def observe(self, time, values):
        self.check()

    def observe_rows(self, rows):
        self.check()
