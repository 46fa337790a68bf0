"""pythonfmu slaves: thin FMI wrappers around crane_fmu.model."""
