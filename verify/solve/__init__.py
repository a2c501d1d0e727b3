"""Solvers: the LPs (7)-(12) of 000, the sphere of 001, the exchange method, exact and interval arithmetic,
plan search."""
