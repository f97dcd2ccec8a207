"""ejsrl.vision."""
