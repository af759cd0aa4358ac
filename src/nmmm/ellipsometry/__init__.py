"""nmmm.ellipsometry."""
