"""A user's regulation-only controller built with stock pythonfmu: no x_d, no planner inputs.

Its inputs are the measured state, its output u; it holds the crane at x = 0 (the
LQR's gains of the Section V crane, rounded, limited to |u| <= 2 m/s2). It is a
crane controller that does not move loads: the scoreboard scores it where its
interface allows (S1, S6) and shows the rest as not applicable.
"""

from pythonfmu import Fmi2Causality, Fmi2Slave, Real

MEASURED = ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2")
GAINS = (31.2, 27.8, -164.2, 3.6, 52.8, 2.1)


class UserLqr(Fmi2Slave):
    author = "a user"
    description = "Regulation-only state feedback for the double-pendulum crane"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.x = self.dx = self.theta1 = self.dtheta1 = self.theta2 = self.dtheta2 = 0.0
        for name in MEASURED:
            self.register_variable(Real(name, causality=Fmi2Causality.input, description=f"measured {name}"))
        self.register_variable(Real("u", causality=Fmi2Causality.output, getter=self.control,
                                    description="demanded trolley acceleration [m/s2]"))

    def control(self):
        state = (self.x, self.dx, self.theta1, self.dtheta1, self.theta2, self.dtheta2)
        return max(-2.0, min(2.0, -sum(k * s for k, s in zip(GAINS, state))))

    def do_step(self, current_time, step_size):
        return True
