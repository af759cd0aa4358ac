"""nmmm.experiment."""
