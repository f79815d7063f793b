"""Seeded generators of synthetic recordings with known truth, for tests and checks."""
