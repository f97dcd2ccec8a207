"""The Jinja2 templates of generated apps (a package so the wheel carries them)."""
