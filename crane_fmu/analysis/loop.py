"""The closed loop of a system's plant and controller, linearised at an operating point: poles, damping, margins.

Sampled-data, as the master runs it: the controller (any FMU, or a law file) is a discrete map at the
communication step ``h``, and the plant's input ``u`` is held over each step. So:

1. the plant is linearised at the operating point (:func:`crane_fmu.analysis.linearize.linearize`) and
   discretised with a zero-order hold at ``h``: ``x[k+1] = Phi x[k] + Gamma u[k]``, ``y[k] = C x[k] + D u[k]``
   for the outputs the controller reads;
2. the controller is linearised by central differences of its step map, seen from outside: from the
   operating point, a pulse ``+-delta`` on one input at ``k = 0`` (the others held), its ``u`` over ``N`` steps
   gives the impulse response ``H[i]`` (``u[k] = sum_i H[i] y[k-i]``: the first ``H[0]`` is its direct
   feedthrough, the rest its memory; a static law has ``H[i] = 0`` for ``i > 0``). A response that has not
   died out within the window (below ``1e-9`` of its peak) is kept only if its last half is one geometric mode
   ``H[i] = g r^(i - M)`` from some row ``M`` on (an integrator: ``r = 1``; a first-order lag: ``0 < r < 1``),
   which the model then continues for ever: ``K(z)`` gains ``g z^-M / (1 - r z^-1)``, the loop one state.
   Any other response cut off by the window would stand for a different controller (an integrator made a
   finite average): the analysis refuses it rather than give a verdict on it;
3. the discrete loop broken at ``u``: ``L(z) = -K(z) G(z)``, ``K(z) = sum_i H[i] z^-i`` (+ the tail),
   ``G(z) = C (zI - Phi)^-1 Gamma + D``; the closed loop ``1 + L = 0``. Its poles are the eigenvalues of the
   loop's state matrix (the plant's state and the controller's last ``N - 1`` inputs), each also given as
   ``s = ln(z) / h`` with its damping ``-Re s / |s|``; the gain and phase margins and the peak of
   ``|S| = |1 / (1 + L)|`` are read on ``z = exp(j w h)`` up to the Nyquist frequency ``pi / h``.

Valid for small deviations from the operating point: a limit the law reaches there (``|u| = u_max``) makes
its gain zero, which the report shows as an open loop.
"""

from collections import namedtuple
from pathlib import Path

import numpy as np

LoopAnalysis = namedtuple("LoopAnalysis", "h poles K H G_parts margins frequencies L point controller plant inputs "
                                          "memory tail", defaults=(None,))
Tail = namedtuple("Tail", "gain ratio")  # H[i] = gain * ratio**(i - M) for i >= M = len(H): the response's last mode
Margins = namedtuple("Margins", "gain_margin gain_crossover phase_margin_deg phase_crossover sensitivity_peak "
                                "sensitivity_at")
MEMORY = 0.5  # s: the longest controller memory measured (its impulse response)
DELTA = 1e-6  # relative pulse of the controller's inputs
LARGEST = 6000  # the most states of the controller's memory (p inputs x N steps) the analysis takes
DECAYED = 1e-9  # a response below this fraction of its peak is zero (died out)
FIT = 1e-6  # a tail is one mode if each row is ratio x the one before within this fraction of the tail's size
NOISE = 1e-11  # ... or within this fraction of the response's peak (its central differences' rounding)


def discretise(A, B, h):
    """``(Phi, Gamma)`` of ``x' = A x + B u`` with ``u`` held over ``h`` (the block matrix exponential)."""
    from scipy.linalg import expm

    n, m = B.shape
    block = np.zeros((n + m, n + m))
    block[:n, :n], block[:n, n:] = A, B
    e = expm(block * h)
    return e[:n, :n], e[:n, n:]


def impulse_response(run, point, names, steps, delta=DELTA):
    """``H`` (steps x inputs): ``run(pulse) -> u over steps`` with ``pulse = {input: value at k = 0}``; central
    differences of a pulse of ``delta`` (relative, at least ``delta``) on each input in turn."""
    H = np.zeros((steps, len(names)))
    for j, name in enumerate(names):
        d = delta * max(1.0, abs(point[name]))
        up, down = run({name: point[name] + d}), run({name: point[name] - d})
        H[:, j] = (np.asarray(up) - np.asarray(down)) / (2 * d)
    return H


def trimmed(H, tolerance=DECAYED):
    """``H`` without its trailing rows below ``tolerance`` of its largest entry (at least one row)."""
    scale = np.abs(H).max()
    if scale == 0:
        return H[:1]
    rows = np.nonzero(np.abs(H).max(axis=1) > tolerance * scale)[0]
    return H[:rows[-1] + 1]


def tail_of(H, tolerance=FIT):
    """``(H[:M], Tail)`` if ``H`` (``N`` rows) is one geometric mode ``H[i] = g r^(i - M)`` from a row
    ``M <= N / 2`` on (``g = H[M]``, ``r`` real, fitted on the last half), else None."""
    N = H.shape[0]
    last = H[N // 2:]
    scale, peak = np.abs(last).max(), np.abs(H).max()
    if N < 4 or scale <= DECAYED * peak:
        return None
    ratio = float(np.sum(last[1:] * last[:-1]) / np.sum(last[:-1] ** 2))
    fits = np.abs(H[1:] - ratio * H[:-1]).max(axis=1) <= tolerance * scale + NOISE * peak  # row i+1 = ratio x row i
    misses = np.nonzero(~fits)[0]
    start = 1 if len(misses) == 0 else misses[-1] + 1  # H[0] stays: the tail's state sees y up to k - 1
    if start > N // 2:
        return None
    return H[:start], Tail(H[start].copy(), ratio)


def identified(H, controller, h):
    """``(H, tail)``: the controller's response ``H`` trimmed where it has died out (tail None), or cut where it
    becomes one mode (:func:`tail_of`). ValueError (one line) for any other response the window cuts off."""
    short = trimmed(H)
    if short.shape[0] < H.shape[0] or H.shape[0] == 1:
        return short, None
    fitted = tail_of(H)
    if fitted is None:
        peak = np.abs(H).max()
        raise ValueError(f"{controller}: its impulse response has not died out within the {H.shape[0] * h:g} s "
                         f"analysed (its last step is {np.abs(H[-1]).max() / peak:.2g} of its peak) and is not one "
                         "mode (an integrator, a first-order lag) that the analysis can continue: no verdict on "
                         "the loop; give a longer window with --memory SECONDS")
    return fitted


def loop_matrix(Phi, Gamma, C, H, tail=None):
    """The closed loop's state matrix: the plant's state, then the controller's inputs of the last ``N - 1``
    steps (``H`` has ``N`` rows; ``C``: the plant's outputs the controller reads, no direct feedthrough), then
    with a ``tail`` its sum ``v[k] = sum_(i >= N) g r^(i - N) y[k - i]``: ``v[k+1] = r v[k] + g y[k + 1 - N]``."""
    n, p, N = Phi.shape[0], C.shape[0], H.shape[0]
    size = n + p * max(N - 1, 0) + (tail is not None)
    M = np.zeros((size, size))
    M[:n, :n] = Phi + (Gamma @ H[:1] @ C if N else 0)
    for i in range(1, N):
        M[:n, n + p * (i - 1):n + p * i] = Gamma @ H[i:i + 1]
    if N > 1:
        M[n:n + p, :n] = C
        M[n + p:n + p * (N - 1), n:n + p * (N - 2)] = np.eye(p * (N - 2))
    if tail is not None:
        M[:n, -1:] = Gamma  # u[k] += v[k]
        M[-1, -1] = tail.ratio
        if N <= 1:
            M[-1:, :n] = tail.gain[None, :] @ C  # y[k] itself (N = 0 or 1)
        else:
            M[-1, n + p * (N - 2):n + p * (N - 1)] = tail.gain  # y[k - (N - 1)], the chain's last
    return M


def frequency_response(Phi, Gamma, C, D, H, h, w, tail=None):
    """``L(exp(j w h))`` on the frequencies ``w`` [rad/s]: ``-K(z) G(z)``."""
    n = Phi.shape[0]
    z = np.exp(1j * w * h)
    K = np.exp(-1j * np.outer(w * h, np.arange(H.shape[0]))) @ H  # len(w) x p
    if tail is not None:
        K = K + np.outer(z ** -H.shape[0] / (1 - tail.ratio / z), tail.gain)
    L = np.empty(len(w), complex)
    for k, zk in enumerate(z):
        G = C @ np.linalg.solve(zk * np.eye(n) - Phi, Gamma)[:, 0] + D[:, 0]
        L[k] = -K[k] @ G
    return L


def margins(w, L):
    """:class:`Margins` of the loop ``L`` on the grid ``w``: the gain margin (at the phase crossover closest to
    ``|L| = 1``; inf without one), the phase margin (python-control's ``mod(arg L, 360) - 180`` at the gain
    crossover where it is smallest in magnitude; inf without one), the peak of ``|1 / (1 + L)|``."""
    def crossings(f):
        k = np.nonzero(np.sign(f[:-1]) != np.sign(f[1:]))[0]
        return [(w[i] + (w[i + 1] - w[i]) * f[i] / (f[i] - f[i + 1]), i, f[i] / (f[i] - f[i + 1])) for i in k]

    def at(i, t):
        return L[i] + t * (L[i + 1] - L[i])

    gm, wg = np.inf, np.nan
    for freq, i, t in crossings(L.imag):  # on the real axis, left of the origin: the phase crossover
        value = at(i, t)
        if value.real < 0 and abs(np.log(-1 / value.real)) < abs(np.log(gm)):
            gm, wg = -1 / value.real, freq
    pm, wp = np.inf, np.nan
    for freq, i, t in crossings(np.abs(L) - 1):
        value = at(i, t)
        margin = np.remainder(np.angle(value, deg=True), 360) - 180
        if abs(margin) < abs(pm):
            pm, wp = margin, freq
    S = np.abs(1 / (1 + L))
    return Margins(gm, wg, pm, wp, float(S.max()), float(w[S.argmax()]))


def analyse(plant_lin, u_name, read, controller_H, h, point, controller="controller", plant="plant", w=None,
            source=None):
    """The :class:`LoopAnalysis` of a plant's linearisation ``plant_lin`` (continuous, from
    :func:`~crane_fmu.analysis.linearize.linearize`) closed by a controller's impulse response ``controller_H``
    (steps x inputs) at the step ``h``; ``read`` is ``[(controller input, plant output)]`` in ``H``'s columns;
    ``source``: the controller's FMU or file, for the messages."""
    column = plant_lin.inputs.index(u_name)
    rows = [plant_lin.outputs.index(output) for _, output in read]
    C, D = plant_lin.C[rows], plant_lin.D[rows][:, [column]]
    if np.abs(D).max(initial=0.0) > 0:
        raise ValueError(f"the controller reads {', '.join(o for (_, o), d in zip(read, D[:, 0]) if d)} of the plant, "
                         f"which {u_name} changes at once: an algebraic loop the analysis does not take")
    Phi, Gamma = discretise(plant_lin.A, plant_lin.B[:, [column]], h)
    H, tail = identified(np.asarray(controller_H, float), f"{controller} ({source})" if source else controller, h)
    poles = np.linalg.eigvals(loop_matrix(Phi, Gamma, C, H, tail))
    if w is None:
        w = np.logspace(-2, np.log10(np.pi / h), 6000)[:-1]
    L = frequency_response(Phi, Gamma, C, D, H, h, w, tail)
    K = H[0] if len(H) else tail.gain
    return LoopAnalysis(h, poles, K, H, (Phi, Gamma, C, D), margins(w, L), w, L, point, controller, plant,
                        [i for i, _ in read], len(H), tail)


def continuous(poles, h):
    """``(s, damping, natural frequency [rad/s])`` of discrete poles ``z``: ``s = ln z / h``."""
    with np.errstate(invalid="ignore", divide="ignore"):  # z = 0 (a step's delay): s = -inf
        s = np.log(poles.astype(complex)) / h
        wn = np.abs(s)
        zeta = np.where(wn > 0, -s.real / wn, 1.0)
    return s, zeta, wn


def report(a):
    """The analysis as text: the operating point, the poles, the margins, how the controller was taken."""
    s, zeta, wn = continuous(a.poles, a.h)
    order = np.argsort(-np.abs(a.poles))
    stable = bool(np.all(np.abs(a.poles) < 1))
    m = a.margins
    lines = [f"closed loop of {a.plant} and {a.controller}, broken at the plant's input u, sampled at h = {a.h:g} s",
             "at " + ", ".join(f"{k} = {v:g}" for k, v in a.point.items()),
             f"controller: linearised from its step map (pulses on {', '.join(a.inputs)}); "
             + _memory(a),
             "u[k] = " + " ".join(f"{k:+.6g} {n}" for k, n in zip(a.K, a.inputs))
             + (" + ..." if a.memory > 1 or a.tail is not None else ""),
             f"closed loop: {'stable' if stable else 'UNSTABLE'} (largest |z| = {np.abs(a.poles).max():.6g})",
             f"{'z':>28} {'|z|':>10} {'s = ln(z)/h':>28} {'damping':>9} {'wn [rad/s]':>11}"]
    shown = [i for i in order if a.poles[i].imag >= 0][:12]
    for i in shown:
        z = a.poles[i]
        lines.append(f"{z.real:>13.6g} {z.imag:+13.6g}j {abs(z):>10.6g} {s[i].real:>13.6g} {s[i].imag:+13.6g}j "
                     f"{zeta[i]:>9.4f} {wn[i]:>11.5g}")
    lines.append(f"gain margin: {_db(m.gain_margin)} (x{m.gain_margin:.4g}) at {m.gain_crossover:.5g} rad/s" if
                 np.isfinite(m.gain_margin) else "gain margin: infinite (no phase crossover below pi/h)")
    lines.append(f"phase margin: {m.phase_margin_deg:.4g} deg at {m.phase_crossover:.5g} rad/s" if
                 np.isfinite(m.phase_margin_deg) else "phase margin: infinite (|L| never crosses 1)")
    lines.append(f"sensitivity peak: Ms = {m.sensitivity_peak:.4g} ({_db(m.sensitivity_peak)}) at "
                 f"{m.sensitivity_at:.5g} rad/s")
    if not stable:
        lines.append("(the closed loop is unstable: the margins above are where L crosses, not how far it is from "
                     "instability)")
    return "\n".join(lines)


def _memory(a):
    if a.tail is None:
        return "static at this point (no memory)" if a.memory == 1 else f"memory of {a.memory} steps"
    r = a.tail.ratio
    kind = ("an integrator" if abs(r - 1) < 1e-9 else
            f"time constant {-a.h / np.log(r):.4g} s" if 0 < r < 1 else "growing" if abs(r) > 1 else "alternating")
    steps = f"{a.memory} step" + ("s" if a.memory != 1 else "")
    return (f"memory of {steps}, then for ever one mode, x{r:.9g} a step ({kind}), from "
            + ", ".join(f"{g:+.6g} {n}" for g, n in zip(a.tail.gain, a.inputs) if g))


def _db(value):
    return f"{20 * np.log10(value):.3g} dB"


def plot(a, path, title):
    """Bode (|L|, arg L, |S|) and Nyquist plots of the loop into a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(11, 7))
    mag, phase, nyq = fig.add_subplot(2, 2, 1), fig.add_subplot(2, 2, 3), fig.add_subplot(1, 2, 2)
    mag.loglog(a.frequencies, np.abs(a.L), label="|L|")
    mag.loglog(a.frequencies, np.abs(1 / (1 + a.L)), label="|S| = |1/(1+L)|")
    mag.axhline(1, color="gray", lw=0.5)
    mag.set_ylabel("magnitude")
    mag.legend()
    phase.semilogx(a.frequencies, np.degrees(np.unwrap(np.angle(a.L))))
    phase.axhline(-180, color="gray", lw=0.5)
    phase.set_xlabel("w [rad/s]")
    phase.set_ylabel("arg L [deg]")
    for ax in (mag, phase):
        ax.axvline(np.pi / a.h, color="gray", ls=":", lw=0.8)
    bounded = a.L[np.abs(a.L) < 10]
    for sign in (1, -1):
        nyq.plot(bounded.real, sign * bounded.imag, color="C0", ls="-" if sign > 0 else "--")
    nyq.plot([-1], [0], "r+", ms=12)
    circle = np.exp(1j * np.linspace(0, 2 * np.pi, 200))
    nyq.plot(circle.real, circle.imag, color="gray", lw=0.5)
    nyq.set_aspect("equal")
    nyq.set_xlim(-3, 3)
    nyq.set_ylim(-3, 3)
    nyq.set_title("Nyquist (|L| < 10)")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def of_system(system, fmus, connections, at=None, memory=MEMORY):
    """The :class:`LoopAnalysis` of a prepared system's plant and the controller that feeds its demand, at the
    operating point: the plant at rest at the move's target (every state 0 but the axis position), with the
    values of ``at`` (states of the plant) in place of those named; the controller's references there (its
    position reference at the position, the others 0). ValueError (one line) for a system without such a loop."""
    from crane_fmu import components, systems
    from crane_fmu.analysis import linearize as lin

    kinds = systems.kinds(system)
    plant = components.by_role(kinds).get("plant")
    if plant is None:
        raise ValueError(f"system {system.name} has no plant: no loop to analyse")
    crane = components.get(kinds[plant]).crane
    if len(crane.demands) != 1:
        raise ValueError(f"{kinds[plant]} has the demands {', '.join(crane.demands)}: the loop analysis takes one")
    u = crane.demands[0]
    controller = next((c.source for c in connections if c.target == plant and c.input == u), None)
    if controller is None:
        raise ValueError(f"system {system.name}: nothing feeds {plant}.{u}: no loop to analyse")
    read = [(c.input, c.output) for c in connections if c.source == plant and c.target == controller]
    if not read:
        raise ValueError(f"system {system.name}: {controller} reads nothing of {plant} (it is fed by "
                         f"{', '.join(sorted({c.source for c in connections if c.target == controller}))}): the loop "
                         "analysis takes a controller that reads the plant")
    axis = crane.axes[0]
    target = systems.move_target(system)
    point = {name: 0.0 for name in crane.state}
    point.update({a.position: target[a.position] for a in crane.axes})
    unknown = [name for name in (at or {}) if name not in point]
    if unknown:
        raise ValueError(f"--at {unknown[0]}: not a state of {kinds[plant]} ({', '.join(point)})")
    point.update(at or {})
    starts = {f"{name}{sep}0" for name in point for sep in ("", "_")}  # the point sets the states, not these
    plant_lin = lin.linearize(fmus[plant], point, {k: v for k, v in system.parameters.get(plant, {}).items()
                                                   if k not in starts})
    x = np.array([plant_lin.point[n] for n in plant_lin.states])
    v = np.array([plant_lin.point[n] for n in plant_lin.inputs])
    y = plant_lin.C @ x + plant_lin.D @ v
    held = {name: y[plant_lin.outputs.index(output)] for name, output in read}
    fed = {c.input for c in connections if c.target == controller}
    refs = {name: (point[axis.position] if name == axis.references[0] else 0.0)
            for name in _references(crane) if name in fed and name not in held}
    names = [name for name, _ in read]
    steps = max(1, round(memory / system.step))
    if steps * len(names) > LARGEST:
        raise ValueError(f"--memory {memory:g} s: {steps} steps x {len(names)} inputs of {controller} make "
                         f"{steps * len(names)} states, more than the {LARGEST} the analysis takes (--memory <= "
                         f"{LARGEST // len(names) * system.step:g} s at h = {system.step:g} s)")
    values = system.parameters.get(controller, {})

    def run(pulse):
        from crane_fmu.cosim import open_instance

        inst = open_instance(fmus[controller], controller)
        try:
            inst.setup(0.0)
            for name, value in values.items():
                inst.set(name, value)
            inst.enter_initialization()
            for name, value in {**refs, **held}.items():
                inst.set(name, value)
            inst.exit_initialization()
            out = []
            for k in range(steps):
                for name, value in held.items():
                    inst.set(name, pulse.get(name, value) if k == 0 else value)
                out.append(inst.get(u))
                inst.do_step(k * system.step, system.step)
            return out
        finally:
            inst.free()

    H = impulse_response(run, held, names, steps)
    shown = {**{n: plant_lin.point[n] for n in crane.state}, **refs}
    source = system.instances.get(controller)
    return analyse(plant_lin, u, read, H, system.step, shown, controller, plant,
                   source=Path(str(source)).name if source else None)


def _references(crane):
    from crane_fmu.controller_interface import references

    return references(crane)
