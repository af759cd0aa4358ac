"""nmmm.recipes."""
