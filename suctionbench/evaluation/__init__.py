"""The benchmark: tasks, the trial runner (one MCAP log per trial), metrics and tables."""
