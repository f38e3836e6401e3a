from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FIXTURES = ROOT / "fixtures"
RAPID_FIXTURES = sorted((FIXTURES / "rapid").iterdir())
INVALID_FIXTURES = sorted((FIXTURES / "invalid").iterdir())


@pytest.fixture
def fixtures_dir() -> Path:
    return FIXTURES
