"""Sensing: camera models and presets, depth rendering, noise, grasp thumbnails."""
