"""Workflows that run the sim to produce data: `sortbot collect` and its engines."""
