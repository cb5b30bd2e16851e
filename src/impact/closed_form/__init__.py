"""Answers without simulation: Masri's two-impacts-per-cycle orbit and its stability, the TMD's optimum."""
