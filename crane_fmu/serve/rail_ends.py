"""A served crane's trolley kept where its drive can still stop it before a rail end (``serve``'s guard).

The plant refuses a step in which the trolley would pass a rail end (``plant_limits.past_rail_end``). A client
writes the drive's demand within its limit ``<demand>_max``; that alone does not keep a run going: a trolley
driven towards a rail end until it is closer than its braking distance reaches it whatever is written next, and
every step after that is refused: the run holds for ever. This guard, given to the runner
(:class:`~crane_fmu.cosim.realtime.Runner`'s ``guard``), refuses the block of steps that ends where the trolley
could no longer stop before a rail end (rolled back as the plant's refusals are), and while the run is held after
a refusal it brakes the trolley to rest at its drive limit, cycle by cycle, until the client writes again.

Per guarded axis (a crane role :class:`~crane_fmu.model.component.Axis` with a finite rail end, whichever instance
feeds its demand): the demand's limit ``U`` is the smaller of the plant's ``<demand>_max`` and, where the external
instance writes the demand, the written range (:mod:`crane_fmu.cosim.write_ranges`), else the feeding instance's own
limit (its ``<demand>_max`` or ``u_max``, where it has one). Where the client writes a reference (``--external
planner``) and a controller drives, a refused block holds the client's outputs at zero: the controller, given the
target 0, brakes at its limit. The trolley's acceleration is the
demand held over each cycle of length ``T``, so that braking at ``-U`` until the speed is within ``U*T`` and then
at ``-v/T`` (rest at the cycle's end) travels :func:`braking_distance`. A block is refused when it ends with that
distance reaching past ``rail end -+ MARGIN`` and farther than it began (a run started within its braking
distance may still brake).

A drive with a lag ``tau > 0`` (the acceleration ``a`` follows the demand ``d`` by ``a' = (d - a) / tau``) is
guarded too. The plant does not serve ``a``; the guard follows it from the demands (the plant's start: ``a = 0``),
exactly: over a block of ``h`` seconds at ``d``, ``a <- d + (a - d) exp(-h / tau)``. With ``s = v + a tau`` (the
speed the trolley tends to with ``d = 0``), ``s' = a + tau a' = d``: ``s`` moves as an unlagged trolley's speed,
so the hold brakes ``s`` as it brakes ``v`` without a lag, and since ``x' = v = s - a tau``,
``x(t) = x + tau v + integral of s - tau s(t) + tau^2 a(t)``. Braked so, ``s`` keeps its sign and goes to rest:
the trolley never passes ``x + tau v + U tau^2 + braking_distance(s)`` (``s >= 0``) or ``x - tau^2 (a - U)``
(``s < 0``), with ``|a| <= U`` (:func:`lagged_reach`); the mirror bound holds towards ``<position>_min``. Both
ends are checked. Braked by the hold the bound does not move from one cycle to the next (the integral of ``s``
it has travelled is what ``braking_distance`` lost); the plant's sub-steps, which take the mean acceleration of
each, move it by at most ``|a - d| dt^3 / (12 tau)`` per sub-step ``dt``, allowed for in the slack.
"""

import math

MARGIN = 1e-6  # m: the rest point kept this far inside the rail end (the plant refuses x > x_max by any amount)
SLACK = 1e-9  # m: a block ends "farther" than it began by more than this (the braking hold's own rounding)
AT_REST = 1e-12  # m/s: a speed within rounding of rest is held at zero (-v/T of a denormal speed is not)


class CannotStop(ValueError):
    """A served run's start from which the trolley cannot stop before a rail end, whatever is written."""


def braking_distance(speed, limit, cycle):
    """The distance [m] a trolley at ``speed`` [m/s] travels braked as :meth:`RailGuard.hold` brakes it: ``-U``
    (``limit``, m/s2) for each whole cycle of ``cycle`` [s] while ``|v| > U*T``, then ``-v/T`` for one cycle.

    With ``n`` whole cycles and ``r = |v| - n U T`` left, it is ``n |v| T - U T^2 n^2 / 2 + r T / 2`` (each cycle
    ``v_i T - U T^2 / 2`` from ``v_i = |v| - i U T``, the last ``r T / 2``)."""
    v, step = abs(speed), limit * cycle
    n = max(0, math.ceil(v / step) - 1) if step > 0 else 0
    r = v - n * step
    return n * v * cycle - limit * cycle * cycle * n * n / 2 + r * cycle / 2


def lagged_reach(x, v, a, tau, limit, cycle):
    """``(farthest, least)`` position [m] a trolley at ``x`` moving at ``v`` with its lagging drive's acceleration
    ``a`` (lag ``tau`` [s], ``|a| <= limit``) reaches when :meth:`RailGuard.hold` brakes it (module docstring)."""
    s, slack = v + a * tau, limit * tau * tau
    ahead = braking_distance(s, limit, cycle) if s >= 0 else -tau * s
    behind = braking_distance(s, limit, cycle) if s <= 0 else tau * s
    return x + tau * v + slack + ahead, x + tau * v - slack - behind


class RailGuard:
    """The runner's guard for the trolley's axes of ``plant`` (instance name) while the instance ``external`` (name)
    is served to a client; ``axes`` are the plant's crane role axes, ``connections`` the system's."""

    def __init__(self, plant, axes, external, connections):
        self.plant, self.external = plant, external
        fed = {c.input: (c.source, c.output) for c in connections if c.target == plant}
        self.axes = [(a, *fed[a.demand]) for a in axes if a.demand in fed]
        self.guarded, self.notes, self.lags = [], [], {}

    def start(self, master, cycle, ranges):
        """Read the limits in effect once initialised; ``cycle`` [s] is the length over which a demand is held."""
        plant = master.instances[self.plant]
        names = list(master.output_names)
        self.cycle = cycle
        for axis, source, output in self.axes:
            low, high = (float(plant.get(f"{axis.position}_{end}")) for end in ("min", "max"))
            lag = next((f"tau{suffix}" for suffix in ("", f"_{axis.position}") if f"tau{suffix}" in plant.variables),
                       None)
            limit = abs(float(plant.get(f"{axis.demand}_max")))
            if source == self.external:
                written = ranges.get(f"{source}.{output}", (-math.inf, math.inf))
                limit = min(limit, -written[0], written[1])
            else:  # a controller drives: it brakes at its own limit at most
                driver = master.instances[source]
                own = next((n for n in (f"{axis.demand}_max", "u_max") if n in getattr(driver, "variables", ())), None)
                limit = min(limit, abs(float(driver.get(own)))) if own else limit
            if not (abs(low) < 1e60 or abs(high) < 1e60) or not 0 < limit < math.inf:
                continue
            tau = float(plant.get(lag)) if lag is not None else 0.0
            if tau > 0:  # followed from the demands: (tau, plant's limit, its sub-step, index of the demand, a)
                self.lags[len(self.guarded)] = [tau, abs(float(plant.get(f"{axis.demand}_max"))),
                                                float(plant.get("max_substep")), names.index(f"{source}.{output}"), 0.0]
            self.guarded.append((axis, output if source == self.external else None,
                                 names.index(f"{self.plant}.{axis.position}"),
                                 names.index(f"{self.plant}.{axis.velocity}"), low, high, limit))
            x, v, most = float(plant.get(axis.position)), float(plant.get(axis.velocity)), \
                abs(float(plant.get(f"{axis.demand}_max")))
            rest = x + v * abs(v) / (2 * most) if most > 0 else x + math.copysign(math.inf, v) if v else x
            if not low <= rest <= high:  # braked at the drive's limit from the first instant: past the rail end
                end = f"{axis.position}_max = {high:g}" if rest > high else f"{axis.position}_min = {low:g}"
                raise CannotStop(f"the trolley starts at {axis.position} = {x:g} m moving at {v:g} m/s: braked at its "
                                 f"drive's {most:g} m/s2 from the start it comes to rest at {rest:g} m, past the rail "
                                 f"end {end} m; no run can step from there")

    def _margins(self, values, drives=None):
        """Per guarded axis: ``(room, name of the rail end, its position)``: how far inside ``end -+ MARGIN`` the
        trolley comes to rest when braked now (negative: past it); ``drives``: a lagging axis' acceleration."""
        found = []
        for k, (axis, _, at, speed, low, high, limit) in enumerate(self.guarded):
            x, v = values[at], values[speed]
            if k in self.lags:
                farthest, least = lagged_reach(x, v, (drives or {}).get(k, self.lags[k][4]), self.lags[k][0], limit,
                                               self.cycle)
                found.append(min((high - MARGIN - farthest, f"{axis.position}_max", high),
                                 (least - (low + MARGIN), f"{axis.position}_min", low)))
                continue
            d = braking_distance(v, limit, self.cycle)
            if v >= 0:
                found.append((high - MARGIN - (x + d), f"{axis.position}_max", high))
            else:
                found.append((x - d - (low + MARGIN), f"{axis.position}_min", low))
        return found

    def refuses(self, before, after, seconds=None):
        """The line refusing a block (of ``seconds``, one cycle if None) that ends where the trolley cannot stop
        before a rail end (and farther than it began), else None."""
        seconds = self.cycle if seconds is None else seconds
        drives, slack = {}, {}
        for k, (tau, most, substep, demand, a) in self.lags.items():
            d = min(max(after[demand], -most), most)  # the demand held over the block, as the plant limits it
            drives[k] = d + (a - d) * math.exp(-seconds / tau)
            slack[k] = 2 * most * substep * substep * seconds / (12 * tau)  # the plant's sub-steps (<= max_substep)
        for k, ((room, end, at), (room_before, _, _), (axis, _, i, j, _, _, limit)) in enumerate(zip(
                self._margins(after, drives), self._margins(before), self.guarded)):
            if room < 0 and room < room_before - SLACK - slack.get(k, 0.0):
                rest = at - MARGIN - room if end.endswith("_max") else at + MARGIN + room
                return (f"the trolley at {axis.position} = {after[i]!r} m moving at {after[j]!r} m/s could not stop "
                        f"before the rail end {end} = {at!r} m with its drive's {limit:g} m/s2 (braked at once it "
                        f"comes to rest at {axis.position} = {rest!r} m; the guard keeps {MARGIN:g} m inside)")
        for k, a in drives.items():  # the block is taken
            self.lags[k][4] = a
        return None

    def hold(self, values):
        """``{external output: demand}`` braking each guarded axis to rest (see :func:`braking_distance`)."""
        held = {}
        for k, (_, output, _, speed, _, _, limit) in enumerate(self.guarded):
            if output is None:  # a controller drives this axis: the client's outputs are held at zero
                continue
            v = values[speed] + (self.lags[k][4] * self.lags[k][0] if k in self.lags else 0.0)  # s = v + a tau
            held[output] = -math.copysign(min(limit, abs(v) / self.cycle), v) if abs(v) > AT_REST else 0.0
        return held
