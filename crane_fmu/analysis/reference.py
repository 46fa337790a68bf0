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


def sampled_closed_loop(state0, p, gains, step, n_steps, mode="gauss-seidel"):
    """Exact sampled-data closed loop: u from the law, held over each step.

    Parameters
    ----------
    mode : {"gauss-seidel", "jacobi"}
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
        measured = states[k] if mode == "gauss-seidel" else previous
        u = backstepping.control(tuple(measured), p, gains)
        sol = solve_ivp(lambda t, s, u=u: plant.derivative(s, u, p), (0.0, step), states[k],
                        method="DOP853", rtol=RTOL, atol=ATOL)
        previous = states[k]
        states[k + 1] = sol.y[:, -1]
        inputs[k] = u
    return states, inputs
