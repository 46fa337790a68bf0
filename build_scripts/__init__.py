"""Builds the FMUs of registered components and the system files (installed as crane_fmu.build_scripts)."""
