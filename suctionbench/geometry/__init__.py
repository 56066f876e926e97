"""Geometry: mesh loading and validation, ray casting, rotations and frames, grasp sampling."""
