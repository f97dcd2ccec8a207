"""Helpers of the FMU tests: small specs beside a copy of lab 8's joint-drives FMU (its C sources)."""

from __future__ import annotations

import shutil
import textwrap
from pathlib import Path

from testkit import EXAMPLES

#: lab 8's FMU, kept as an unpacked FMU with C sources (the build compiles it)
DRIVES = EXAMPLES / "paper" / "fmu_motor_control" / "joint_drives"


def fmu_folder(tmp_path: Path, name: str = "drives") -> Path:
    """A copy of the joint-drives FMU folder in ``tmp_path`` (to edit or pack)."""
    dest = tmp_path / name
    if not dest.exists():
        shutil.copytree(DRIVES, dest, ignore=shutil.ignore_patterns("binaries"))
    return dest


def write_spec(tmp_path: Path, text: str, name: str = "lab.ejs.yaml") -> Path:
    """Write a spec (dedented) into ``tmp_path`` beside a copy of the FMU folder ``drives``."""
    fmu_folder(tmp_path)
    spec = tmp_path / name
    spec.write_text(textwrap.dedent(text).lstrip(), encoding="utf-8")
    return spec


def build_spec(tmp_path: Path, text: str) -> Path:
    """Build a spec written beside the FMU folder; returns the app folder."""
    from ejsgen.cli import build

    spec = write_spec(tmp_path, text)
    return build(spec, tmp_path / "app")


#: a co-simulation of the drives alone: joint 1 gets a set point ``ref``, the arm stands still
CS_SPEC = """
ejs: 1
title: Drives alone (co-simulation)
model:
  variables:
    t: 0.0
    dt: 0.01
    ref: 1.0
    i_max: 1000.0
    Kd: 0.4
    tau: [0.0, 0.0, 0.0]
    V: [0.0, 0.0, 0.0]
  evolution:
    - code: t = t + dt
fmus:
  drives:
    file: drives
    kind: co_simulation
    {step}
    inputs: {{q_ref1: ref}}
    outputs: {{tau1: "tau[0]", V1: "V[0]"}}
    parameters: {{i_max: i_max, Kd: Kd}}
"""


def cs_spec(step: str = "") -> str:
    """``CS_SPEC`` with an optional ``step:`` line (the communication step)."""
    return CS_SPEC.format(step=f"step: {step}" if step else "")
