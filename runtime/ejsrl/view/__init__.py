"""ejsrl.view."""
