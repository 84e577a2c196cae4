"""Where the shipped data lives: ``models/`` and ``experiments/`` beside the package."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODELS_DIR = ROOT / "models"
EXPERIMENTS_DIR = ROOT / "experiments"
SCENARIOS_DIR = EXPERIMENTS_DIR / "scenarios"


def model_path(name: str) -> Path:
    """Path of a shipped spacecraft model, by file name or stem (``"cassini_post_probe"``)."""
    p = Path(name)
    if p.suffix != ".toml":
        p = p.with_suffix(".toml")
    return p if p.is_absolute() or p.exists() else MODELS_DIR / p.name
