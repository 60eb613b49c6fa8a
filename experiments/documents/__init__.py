"""The documents' generated figures and texts, written from committed results."""
