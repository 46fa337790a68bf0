"""The kinds of FMU the build makes, for the tests that hold every kind to one rule (the standard's state table,
the fuzzers, the plant's physics): ``kind: (folder under build/ of its FMI 2.0 FMUs, of its FMI 3.0 ones)``.

A new kind of FMU is one entry here; the tests parametrised over it then run on it too (the ``fmu_kinds`` and
``plant_dir`` fixtures of conftest.py give the folders of a run's build).
"""

FMU_KINDS = {"python": ("fmus", "fmi3"), "native": ("native", "native/fmi3")}
