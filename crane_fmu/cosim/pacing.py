"""Real-time pacing against absolute deadlines, the timing it measures, and the client watchdog.

Pure logic over a clock and a sleep function (``time.monotonic`` and ``time.sleep`` by default),
so that tests drive it exactly with a fake clock.

Cycle ``j`` is released at the deadline ``d_j = t0 + j*period`` (from the integer ``j``: never a
``sleep(period)`` whose errors add up). Its *lateness* is how long after ``d_j`` its work began (the
wake-up delay, or the backlog of a late cycle before it); it is *on time* when its work ended by the
next deadline ``d_(j+1)``, else a *deadline miss*. A late cycle runs at once: deadlines stay on the
grid, so the cycles catch up with the wall clock instead of drifting behind it.
"""

import math
import os
import time
from array import array


class Timing:
    """Per-cycle lateness, work time and misses; their summary; the CSV of every cycle.

    Attributes
    ----------
    period : float
        The cycle's period [s].
    deadlines, lateness, work : array of float
        Per cycle: the deadline after the first one, how late the work began, how long it took [s].
    missed : array of int
        Per cycle: 1 where the work ended after the next deadline.
    """

    def __init__(self, period):
        self.period = period
        self.deadlines, self.lateness, self.work = array("d"), array("d"), array("d")
        self.missed = array("b")
        self.misses = 0
        self.end = 0.0  # when the last cycle's work ended, from the first deadline [s]

    def add(self, deadline, lateness, work):
        """Record one cycle: its deadline (from the first), lateness and work time [s]."""
        self.deadlines.append(deadline)
        self.lateness.append(lateness)
        self.work.append(work)
        missed = lateness + work > self.period
        self.end = deadline + lateness + work
        self.missed.append(missed)
        self.misses += missed

    def __len__(self):
        return len(self.lateness)

    def summary(self):
        """``{cycles, misses, on_time (fraction), lateness_p50, lateness_p99, lateness_max, work_p50 [s]}``."""
        n = len(self)
        return {"cycles": n, "misses": self.misses, "on_time": 1.0 - self.misses / n if n else math.nan,
                "lateness_p50": percentile(self.lateness, 50), "lateness_p99": percentile(self.lateness, 99),
                "lateness_max": max(self.lateness, default=math.nan), "work_p50": percentile(self.work, 50)}

    def wall(self):
        """The wall time the cycles took [s]: from the first deadline to the end of the last cycle's period, or
        of its work if that ended later."""
        return max(self.end, self.deadlines[-1] + self.period) if len(self) else 0.0

    def describe(self, simulated=None):
        """One line: cycles, lateness percentiles, misses and, given the simulated time the cycles advanced, the
        real-time factor: that time over the :meth:`wall` time (1 when the cycles kept up)."""
        if not len(self):
            return f"no cycle of {self.period * 1e3:g} ms"
        s = self.summary()
        line = (f"{s['cycles']} cycles of {self.period * 1e3:g} ms: lateness p50 {s['lateness_p50'] * 1e3:.3f} ms, "
                f"p99 {s['lateness_p99'] * 1e3:.3f} ms, max {s['lateness_max'] * 1e3:.3f} ms; "
                f"{s['misses']} deadline misses ({100 * (1 - s['on_time']):.2f} %)")
        if simulated is not None and len(self):
            line += f"; real-time factor {simulated / self.wall():.4f}"
        return line

    def write_csv(self, path, start_time=0.0):
        """Every cycle as a CSV row: ``cycle, deadline_s, lateness_s, work_s, missed, time`` (the simulated time
        the cycle started from, with cycles of ``period`` from ``start_time``), written aside and renamed."""
        partial = f"{path}.partial"
        with open(partial, "w") as f:
            f.write("cycle,deadline_s,lateness_s,work_s,missed,time\n")
            for j, (d, lat, w, m) in enumerate(zip(self.deadlines, self.lateness, self.work, self.missed)):
                f.write(f"{j},{d!r},{lat!r},{w!r},{m},{start_time + j * self.period!r}\n")
        os.replace(partial, path)


def percentile(values, q):
    """The ``q``-th percentile of ``values`` (linear between the nearest ranks, as numpy's default); nan if none."""
    ordered = sorted(values)
    if not ordered:
        return math.nan
    position = (len(ordered) - 1) * q / 100
    low = math.floor(position)
    high = min(low + 1, len(ordered) - 1)
    return ordered[low] + (ordered[high] - ordered[low]) * (position - low)


class Pacer:
    """Runs cycles of work at absolute deadlines ``t0 + j*period``, recording their :class:`Timing`.

    Parameters
    ----------
    period : float
        [s], > 0.
    clock : callable
        Seconds, monotonic (default ``time.monotonic``).
    sleep : callable
        ``sleep(seconds)``; a sleep that returns True (as ``threading.Event.wait`` does when the event is
        set) stops the pacing.
    """

    def __init__(self, period, clock=time.monotonic, sleep=time.sleep):
        if not period > 0:
            raise ValueError(f"period must be > 0, got {period!r}")
        self.period, self.clock, self.sleep = period, clock, sleep
        self.timing = Timing(period)
        self.origin = None  # t0, set by the first cycle
        self.cycles = 0

    def cycle(self, work):
        """Wait for the next deadline, run ``work()`` and record the cycle; False (no work run) if the sleep
        said stop."""
        if self.origin is None:
            self.origin = self.clock()
        deadline = self.origin + self.cycles * self.period
        while (now := self.clock()) < deadline:
            if self.sleep(deadline - now):
                return False
        work()
        self.timing.add(self.cycles * self.period, now - deadline, self.clock() - now)
        self.cycles += 1
        return True


class Watchdog:
    """Notices a client that has fallen silent: no write for longer than ``timeout``.

    Parameters
    ----------
    timeout : float
        [s], > 0.
    hold : str
        What the external inputs do while the client is silent: ``"zero"`` (set to 0) or ``"last"``
        (keep the last values written).
    """

    HOLDS = ("zero", "last")

    def __init__(self, timeout, hold="zero"):
        if not timeout > 0 or not math.isfinite(timeout):
            raise ValueError(f"watchdog timeout must be > 0 and finite, got {timeout!r}")
        if hold not in self.HOLDS:
            raise ValueError(f"hold must be one of {', '.join(self.HOLDS)}, got {hold!r}")
        self.timeout, self.hold = timeout, hold
        self.holding = False

    def check(self, now, last_write):
        """``"hold"`` when the client has just fallen silent, ``"resume"`` when it has just written again after
        that, else None."""
        silent = now - last_write > self.timeout
        if silent != self.holding:
            self.holding = silent
            return "hold" if silent else "resume"
        return None

    def describe(self, silent_for, what):
        """The line that says the watchdog holds ``what`` (e.g. ``"the external instance's outputs"``)."""
        held = "at zero" if self.hold == "zero" else "at their last values"
        return f"no client write for {silent_for:.3g} s (watchdog {self.timeout:g} s): {what} held {held}"
