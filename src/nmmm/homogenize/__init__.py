"""nmmm.homogenize."""
