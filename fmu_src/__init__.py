"""The FMI side: one FMI framework in C for every FMU, the models behind it (native, Python, a system), and the
Python runtime of the Python FMUs (python/).

This folder is installed as the package ``crane_fmu.fmu_src`` (pyproject.toml's package-dir maps it), so that a
wheel adds no top-level module of this name: import it by that name, ``crane_fmu.fmu_src.python.runtime``.
"""
