"""Runtime core: parameters, equations of motion, control law, FMU variable tables.

Standard library only, and no module-level mutable state: the built FMUs bundle
this package and run inside whatever Python process hosts them.
"""
