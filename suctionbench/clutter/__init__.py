"""Bin picking in clutter (Dex-Net 3.0's future work): a pick bin filled with several objects,
picked one attempt after another.

Data flow, one module each: `tasks` (tasks/bin-*.toml: which objects fill each bin) -> `scene`
(the pick bin in the workspace) -> `episode` (filling the bin, one attempt, what left the bin) ->
`planning` (image policies per object region; the known-state policy with path checks) ->
`runner` (one bin end to end, labels beside outcomes) -> `benchmark` (`eval --task bin-*`: every
bin, MCAP logs, run.json) -> `report` (the report's bin sections). The gymnasium environment is
`suctionbench.envs.suction_bin` (SuctionBin-v3).
"""
