"""A controller FMU of your own, scored by crane-fmu compare: a template to copy.

It has the planar crane's controller interface (crane_fmu/controller_interface.py): the measured
state in, the trolley acceleration u out, the target position x_d as a parameter.
The law is a plain state feedback, u = -k . (x - x_d, dx, theta1, dtheta1, theta2, dtheta2),
limited to |u| <= u_max. Replace it with yours.

Build (pythonfmu only; this file imports nothing of crane_fmu):

    pythonfmu build -f examples/my_controller/my_controller.py --dest build/mine

and score it:

    crane-fmu compare --controller build/mine/MyController.fmu --controller LqrController --out results/mine
"""

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real

MEASURED = ("x", "dx", "theta1", "dtheta1", "theta2", "dtheta2")
# gains of the LQR's design for the Section V crane, rounded: a reasonable start
GAINS = (31.2, 27.8, -164.2, 3.6, 52.8, 2.1)


class MyController(Fmi2Slave):
    author = "you"
    description = "State feedback for the double-pendulum crane (template)"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.x_d, self.u_max, self.max_step = 0.0, 2.0, 0.02
        self.x = self.dx = self.theta1 = self.dtheta1 = self.theta2 = self.dtheta2 = 0.0
        self.register_variable(Real("x_d", causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed,
                                    description="target trolley position [m]"))
        self.register_variable(Real("u_max", causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed,
                                    description="largest |u| [m/s2]"))
        self.register_variable(Real("max_step", causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed,
                                    description="longest communication step this controller accepts [s]"))
        for name in MEASURED:
            self.register_variable(Real(name, causality=Fmi2Causality.input, description=f"measured {name}"))
        self.register_variable(Real("u", causality=Fmi2Causality.output, getter=self.control,
                                    description="demanded trolley acceleration [m/s2]"))

    def control(self):
        error = (self.x - self.x_d, self.dx, self.theta1, self.dtheta1, self.theta2, self.dtheta2)
        u = -sum(k * e for k, e in zip(GAINS, error))
        return max(-self.u_max, min(self.u_max, u))

    def do_step(self, current_time, step_size):
        return step_size <= self.max_step  # a coarser step is refused: the step is discarded
