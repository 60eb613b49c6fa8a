"""The navigation experiment: seeded start/goal episodes measured as nav2 is."""
