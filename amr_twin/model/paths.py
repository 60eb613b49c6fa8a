"""Where the project's data files live (the repository is installed editable)."""

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
MODEL_DIR = ROOT / "models" / "amr"
