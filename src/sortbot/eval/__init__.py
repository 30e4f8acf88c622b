"""Evaluation: run policies over seeded episodes and count what the paper counts."""
