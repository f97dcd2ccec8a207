"""ejsrl.robotics."""
