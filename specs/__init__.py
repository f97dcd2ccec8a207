"""The language reference, the tutorial and the JSON Schema, shipped with the package (`ejsgen docs`)."""
