"""Object sets: procedural generators, the Basic / Typical / Adversarial sets, the training corpus,
mesh import, stable poses, convex decomposition and MuJoCo bodies."""
