"""The FMI side: generic slaves of any component, the C loader and wrapper (installed as crane_fmu.fmu_src)."""
