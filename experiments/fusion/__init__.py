"""Thesis chapter 6 in the twin: one warehouse drive, five localisation estimates."""
