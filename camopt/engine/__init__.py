"""What runs a problem: the driver's ask/evaluate/tell loop, robust evaluation, sweeps,
tolerance analysis, targets and interruption handling."""
