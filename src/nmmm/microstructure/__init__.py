"""nmmm.microstructure."""
