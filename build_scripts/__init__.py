"""Builds the FMUs of registered components and the system files.

This folder is installed as the package ``crane_fmu.build_scripts`` (pyproject.toml's package-dir maps it), so
that a wheel adds no top-level module of this name: import it by that name, ``from crane_fmu.build_scripts
import native``, also from inside this folder.
"""
