"""Runtime core: component descriptors, parameters, equations of motion, control laws.

Standard library only, and no module-level mutable state: the built FMUs bundle
this package and run inside whatever Python process hosts them.
"""

# Import every submodule now. A host shares sys.modules with the FMUs it loads
# and may delete an FMU's extracted folder after freeing it (fmpy's simulate
# does); a submodule imported lazily later would then be looked for there.
from . import (  # noqa: F401
    backstepping,
    benchmark,
    component,
    disturbances,
    energy,
    estimator,
    hard_hit,
    limits,
    linalg,
    lqr,
    parameters,
    planner,
    plant,
    plant3d,
    plant_continuous,
    rules,
    tables,
    wind,
)
