"""Checks shared by the end-to-end tests on what a ``process`` run reports."""
from __future__ import annotations

# Options for runs whose test is about plumbing (files, caches, processes, kills), not about the tile:
# the tiny preset, and the pure SeamlessGAN tile (no lattice cut, no exemplar refinement), which is a
# third of a stack's work at these sizes. Its tiles do not pass (exit 1, every stack "not-passed");
# the lattice and refinement paths and a passed exit 0 are tested on the bundled stacks themselves.
PLUMBING = ("--preset", "tiny", "--refine", "off")


def assert_all_written(code: int, payload: dict) -> None:
    """Everything should work: no error finding, no failed stack, and exit 0 unless a stack did not
    pass (exit 1 then, with every such stack reported not-passed)."""
    errors = [f for f in payload["findings"] if f["severity"] == "error"]
    assert not errors, errors
    statuses = [s["status"] for s in payload["stacks"]]
    assert "failed" not in statuses, payload["stacks"]
    assert code == (1 if "not-passed" in statuses else 0), (code, statuses)
