"""Reference solutions with scipy: the same model functions, a different integrator.

These integrate :func:`crane_fmu.model.plant.derivative` with DOP853 at tight
tolerances, so a difference from the FMUs measures the FMU's RK4 and the
co-simulation, never a second copy of the equations (for that, the tests use
the equations sympy derives, ``tests/test_equations.py``).
"""

import numpy as np
from scipy.integrate import solve_ivp

from crane_fmu.model import backstepping, plant

RTOL = ATOL = 1e-12


def sampled_closed_loop(state0, p, gains, step, n_steps, algorithm="gauss-seidel"):
    """Exact sampled-data closed loop: u from the law, held over each step.

    Parameters
    ----------
    algorithm : {"gauss-seidel", "jacobi"}
        ``gauss-seidel``: ``u_k = law(state_k)``. ``jacobi``: ``u_k =
        law(state_{k-1})`` (``u_0 = law(state_0)``), the one-step lag of a
        Jacobi master on the controller's feedthrough.

    Returns
    -------
    (states, inputs)
        States at ``k*step`` for k = 0..n_steps, shape (n_steps+1, 6), and the
        held inputs, shape (n_steps,).
    """
    states = np.empty((n_steps + 1, 6))
    inputs = np.empty(n_steps)
    states[0] = state0
    previous = state0
    for k in range(n_steps):
        measured = states[k] if algorithm == "gauss-seidel" else previous
        u = backstepping.control(tuple(measured), p, gains)
        sol = solve_ivp(lambda t, s, u=u: plant.derivative(s, u, p), (0.0, step), states[k],
                        method="DOP853", rtol=RTOL, atol=ATOL)
        previous = states[k]
        states[k + 1] = sol.y[:, -1]
        inputs[k] = u
    return states, inputs


def model_exchange(component, values, inputs, times, rtol=1e-10, atol=1e-12, max_events=1000):
    """A component's Model Exchange form integrated by DOP853, stopping at its events as an FMI host does.

    The derivatives, event indicators and event updates of ``component.continuous``, with the
    inputs held; an indicator that falls through zero stops the integration at the first point
    past the crossing (as CVODE's root finding returns it), where the event update runs.

    Parameters
    ----------
    component : Component
        A component with :attr:`~crane_fmu.model.component.Component.continuous`.
    values : dict
        Parameter values (the defaults for the others).
    inputs : tuple
        The input values in table order, held over the run.
    times : array_like
        Increasing output times from 0; the run ends at the last one or where the model ends it.

    Returns
    -------
    (states, outputs, events)
        The continuous states (one row per output time reached) and the outputs there, and the
        events as ``(time, Event)``.
    """
    me = component.continuous
    config = component.check(values)
    times = np.asarray(times, dtype=float)
    event = me.event_update(config, me.initial(config), inputs, me.free_mode, 0.0)
    t, state, mode, events = 0.0, np.array(event.state), event.mode, []
    rows = [] if times[0] > 0 else [state]
    modes = [] if times[0] > 0 else [mode]
    while event.terminate is None and t < times[-1]:
        if len(events) >= max_events:
            raise RuntimeError(f"more than {max_events} events before t = {t!r} s")
        nz = len(me.indicators)

        def indicator(t, s, i, mode=mode):
            return me.indicators_of(config, tuple(s), inputs, mode)[i]

        crossings = [lambda t, s, i=i: indicator(t, s, i) for i in range(nz)]
        for f in crossings:
            f.terminal, f.direction = True, -1
        sol = solve_ivp(lambda t, s, mode=mode: me.derivatives_of(config, tuple(s), inputs, mode),
                        (t, times[-1]), state, method="DOP853", rtol=rtol, atol=atol, events=crossings,
                        dense_output=True)
        end = sol.t[-1]
        inside = times[(times > t) & (times <= end)]
        rows += list(sol.sol(inside).T)
        modes += [mode] * len(inside)
        t, state = end, sol.y[:, -1]
        if sol.status != 1:
            break
        fired = [i for i in range(nz) if len(sol.t_events[i])]
        step = max(abs(t), 1.0) * 1e-15
        while any(indicator(t, state, i) > 0 for i in fired):  # past the crossing
            t += step
            step *= 2.0
            state = sol.sol(t) if t <= end else state + (t - end) * np.array(
                me.derivatives_of(config, tuple(state), inputs, mode))
        t = float(t)
        event = me.event_update(config, tuple(map(float, state)), inputs, mode, t)
        events.append((t, event))
        state, mode = np.array(event.state), event.mode
    outputs = np.array([me.outputs_of(config, tuple(s), inputs, m) for s, m in zip(rows, modes)])
    return np.array(rows), outputs, events
