"""nmmm.ema."""
