"""ejsrl.sim."""
