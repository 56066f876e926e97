"""MuJoCo simulation: YuMi scene, suction cup, IK, pick episodes."""
