"""rapidcomp discover and simulate: name the effect a model misses."""
