"""nmmm.appearance."""
