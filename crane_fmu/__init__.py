"""Double-pendulum overhead crane and backstepping anti-swing controller as FMI co-simulation FMUs.

Importing this package imports nothing outside the standard library.
"""

__version__ = "0.1.0"
