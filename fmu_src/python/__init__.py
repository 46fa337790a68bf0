"""The Python model: the C model over a component's Python runtime, the loaders, and that runtime (slave2, slave3)."""
