"""Where the repository's shipped files are, whatever the test's folder."""

from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
MODELS = REPO_ROOT / "models"
PROBLEMS = REPO_ROOT / "problems"
