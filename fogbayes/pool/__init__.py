"""Pooling across runs and units: hierarchical models of a population of one sensor type."""
