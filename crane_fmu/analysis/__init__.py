"""Analyses on top of the co-simulation: scipy references, metrics, plots, paper reproduction."""
