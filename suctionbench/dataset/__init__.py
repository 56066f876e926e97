"""Dataset generation: Dex-Net tensor storage, generation pipeline, execution engines."""
