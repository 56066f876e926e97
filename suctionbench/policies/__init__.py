"""Grasp policies: heuristics, the GQ-CNN cross-entropy policy, and known-state analytic ranking."""
