"""Continuation of periodic orbits: branches, stability, bifurcations, frequency responses."""
