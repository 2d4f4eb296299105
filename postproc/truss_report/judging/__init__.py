"""The judging layer: statistics of the runs, design loads, the mechanism margins, the
consistency of the file and the verdicts, computed from what the reading layer returns, as
dataclasses. Nothing here formats or writes: this layer imports numpy, scipy, pandas and the
reading layer only."""
