"""Benchmark task definitions (TOML), shipped as package data."""
