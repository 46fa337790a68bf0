"""Double-pendulum overhead crane and backstepping anti-swing controller as FMI co-simulation FMUs.

Importing this package imports nothing outside the standard library.
"""

__version__ = "0.1.0"

DEFAULT_FMU_DIR = "build/fmus"  # where `crane-fmu build` writes the FMI 2.0 FMUs and every command looks first
DEFAULT_SYSTEM = "paper"  # the system every command runs when given none: the paper's Section V
