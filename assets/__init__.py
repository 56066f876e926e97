"""Shipped data: meshes, robot and object assets, pretrained models (package data)."""
