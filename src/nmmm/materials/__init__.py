"""nmmm.materials."""
