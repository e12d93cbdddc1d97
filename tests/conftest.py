"""Shared test configuration: hypothesis profiles and the conformance data location."""
import os
from pathlib import Path

from hypothesis import HealthCheck, settings

settings.register_profile(
    "ci", derandomize=True, deadline=None, max_examples=60,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile("dev", deadline=None, max_examples=60)
# CI (CI=true) runs derandomized: the same examples every run
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci" if os.environ.get("CI") else "dev"))

#: MATLAB reference outputs (never copied into the repository).
CONFORMANCE_DIR = Path(__file__).resolve().parents[1].parent / "shared" / "conformance"
