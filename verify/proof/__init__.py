"""Optimality certificates: `build` makes them from a model, `check` re-checks one without any solver."""
