"""The build checks every FMU a spec names, each problem at the spec line that causes it:
the file is an FMU inside the spec's folder, the kind is one it offers, every variable
exists with the right causality, outputs go to model variables, and the FMU has a binary
for this platform (or C sources the build compiles)."""

from __future__ import annotations

import os
import zipfile
from pathlib import Path

import pytest
from ejsgen.cli import main
from testkit.fmu import cs_spec, fmu_folder, write_spec

ME_SPEC = """
ejs: 1
title: Drives integrated by an ODE page
model:
  variables:
    t: 0.0
    dt: 0.01
    x: 0.0
    tau: [0.0, 0.0, 0.0]
  evolution:
    - ode:
        equations:
          x: "tau[0]"
fmus:
  drives:
    file: drives
    kind: model_exchange
    inputs: {q_ref1: 1.0}
    outputs: {tau1: "tau[0]"}
"""


def first_error(tmp_path: Path, text: str, capsys: pytest.CaptureFixture[str]) -> tuple[Path, str]:
    spec = write_spec(tmp_path, text)
    status = main(["build", str(spec), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert status == 1, err
    assert "Traceback" not in err
    assert not (tmp_path / "out").exists()
    return spec, err.splitlines()[0]


def place(spec: Path, needle: str, at: str | None = None) -> str:
    """``FILE:LINE:COL`` of the first line holding ``needle``, at the first character of ``at`` (default: the needle)."""
    for k, line in enumerate(spec.read_text().splitlines(), 1):
        if needle in line:
            return f"{spec}:{k}:{line.index(at or needle) + 1}"
    raise AssertionError(needle)


def test_an_unknown_fmu_variable_is_named_with_a_suggestion(tmp_path, capsys):
    spec, err = first_error(tmp_path, cs_spec().replace('tau1: "tau[0]"', 'tau4: "tau[0]"'), capsys)
    assert err == f"{place(spec, 'tau4')}: error: the FMU 'drives' has no variable 'tau4'; did you mean 'tau3'?"


@pytest.mark.parametrize(
    "old, new, needle, words",
    [
        ("inputs: {q_ref1: ref}", "inputs: {tau1: ref}", "tau1: ref", "'tau1' is an output of the FMU 'drives', not an input"),
        ('outputs: {tau1: "tau[0]", V1: "V[0]"}', 'outputs: {q1: "tau[0]"}', "q1:", "'q1' is an input of the FMU 'drives', not an output"),
        ("parameters: {i_max: i_max, Kd: Kd}", "parameters: {tau2: 1.0}", "tau2", "'tau2' is an output of the FMU 'drives', not a parameter"),
    ],
)
def test_a_variable_of_the_wrong_causality_is_refused(tmp_path, capsys, old, new, needle, words):
    spec, err = first_error(tmp_path, cs_spec().replace(old, new), capsys)
    assert err.startswith(f"{place(spec, needle)}: error: {words}")


def test_an_output_must_go_to_a_model_variable(tmp_path, capsys):
    spec, err = first_error(tmp_path, cs_spec().replace('V1: "V[0]"', 'V1: "volts"'), capsys)
    where = place(spec, "volts", '"volts"')
    assert err == f"{where}: error: 'volts' is not a model variable; declare it, e.g. 'volts: 0.0'"


def test_a_model_exchange_output_cannot_be_an_ode_state(tmp_path, capsys):
    spec, err = first_error(tmp_path, ME_SPEC.replace('tau1: "tau[0]"', "tau1: x"), capsys)
    assert err.startswith(f"{place(spec, 'tau1: x', 'x}')}: error: 'x' is a state of an ODE page")


def test_a_file_that_is_not_an_fmu_is_refused(tmp_path, capsys):
    (tmp_path / "notes.fmu").write_text("not a zip")
    spec, err = first_error(tmp_path, cs_spec().replace("file: drives", "file: notes.fmu"), capsys)
    assert err.startswith(f"{place(spec, 'notes.fmu')}: error: 'notes.fmu' is not an FMU")


def test_an_fmu_outside_the_specs_folder_is_refused(tmp_path, capsys):
    inner = tmp_path / "lab"
    inner.mkdir()
    fmu_folder(tmp_path, "outside")
    spec, err = first_error(inner, cs_spec().replace("file: drives", "file: ../outside"), capsys)
    assert err == f"{place(spec, '../outside')}: error: the FMU '../outside' must be a path inside the spec's folder; copy the FMU next to the spec (or into a subfolder) and name it relative to the spec"
    os.symlink(tmp_path / "outside", inner / "linked")
    spec, err = first_error(inner, cs_spec().replace("file: drives", "file: linked"), capsys)
    assert err.startswith(f"{place(spec, 'linked')}: error: the FMU 'linked' is a link to a file outside the spec's folder")
    (tmp_path / "elsewhere.fmu").write_bytes(b"PK")
    os.symlink(tmp_path / "elsewhere.fmu", inner / "link.fmu")
    spec, err = first_error(inner, cs_spec().replace("file: drives", "file: link.fmu"), capsys)
    assert err.startswith(f"{place(spec, 'link.fmu')}: error: the FMU 'link.fmu' is a link to a file outside the spec's folder")


def test_an_fmu_without_a_binary_for_this_platform_or_sources_is_refused(tmp_path, capsys):
    from fmpy import platform

    folder = fmu_folder(tmp_path, "src")
    xml = (folder / "modelDescription.xml").read_text().replace('<SourceFiles><File name="joint_drives.c"/></SourceFiles>', "")
    with zipfile.ZipFile(tmp_path / "win_only.fmu", "w") as zf:
        zf.writestr("modelDescription.xml", xml)
        zf.writestr("binaries/win64/joint_drives.dll", b"MZ")
    spec, err = first_error(tmp_path, cs_spec().replace("file: drives", "file: win_only.fmu"), capsys)
    assert err.startswith(f"{place(spec, 'win_only.fmu')}: error: the FMU 'win_only.fmu' has no binary for this platform ({platform}); it has binaries for win64")


def test_a_kind_the_fmu_does_not_offer_is_refused(tmp_path, capsys):
    folder = fmu_folder(tmp_path)
    md = folder / "modelDescription.xml"
    text = md.read_text()
    start, end = text.index("  <CoSimulation"), text.index("</CoSimulation>") + len("</CoSimulation>\n")
    md.write_text(text[:start] + text[end:])
    spec, err = first_error(tmp_path, cs_spec(), capsys)
    assert err == f"{place(spec, 'co_simulation')}: error: the FMU 'drives' has no co-simulation interface; use kind: model_exchange"


def test_c_sources_that_do_not_compile_are_reported_at_the_file_line(tmp_path, capsys):
    folder = fmu_folder(tmp_path)
    source = folder / "sources" / "joint_drives.c"
    source.write_text(source.read_text() + "\nthis is not C;\n")
    spec, err = first_error(tmp_path, cs_spec(), capsys)
    assert err.startswith(f"{place(spec, 'file: drives', 'drives')}: error: cannot compile the C sources of the FMU 'drives': ")
    assert "joint_drives.c" in err and "error" in err.split("drives': ", 1)[1]


def test_a_solver_for_a_model_exchange_fmu_is_refused_where_an_ode_page_integrates_it(tmp_path, capsys):
    spec, err = first_error(tmp_path, ME_SPEC.replace("    kind: model_exchange\n", "    kind: model_exchange\n    method: rk4\n"), capsys)
    assert err == (
        f"{place(spec, 'method: rk4', 'rk4')}: error: 'method' sets the solver of a model-exchange FMU in a model without ODE pages; "
        "this FMU's states are integrated by an ODE page, with that page's method and tolerance; remove 'method'"
    )
    spec, err = first_error(tmp_path, cs_spec().replace("    kind: co_simulation\n", "    kind: co_simulation\n    tolerance: 1.0e-8\n"), capsys)
    assert err.startswith(f"{place(spec, 'tolerance: 1.0e-8', '1.0e-8')}: error: 'tolerance' sets the solver of a model-exchange FMU")
    assert "a co-simulation FMU steps itself" in err


def test_an_invalid_model_description_is_refused_with_fmpys_reason(tmp_path, capsys):
    folder = fmu_folder(tmp_path)
    md = folder / "modelDescription.xml"
    md.write_text(md.read_text().replace('causality="input"', 'causality="inputt"', 1))
    spec, err = first_error(tmp_path, cs_spec(), capsys)
    assert err.startswith(f"{place(spec, 'file: drives', 'drives')}: error: the FMU 'drives'")
    assert "has an invalid modelDescription.xml" in err and "inputt" in err


def test_without_fmpy_the_build_says_how_to_install_it(tmp_path):
    import subprocess
    import sys

    spec = write_spec(tmp_path, cs_spec())
    code = "import sys; sys.modules['fmpy'] = None; from ejsgen.cli import main; sys.exit(main(['validate', sys.argv[1]]))"
    r = subprocess.run([sys.executable, "-P", "-c", code, str(spec)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 1
    assert f"{place(spec, 'file: drives', 'drives')}: error: FMUs need FMPy, which is not installed; pip install 'ejsgen[fmu]' (or pip install fmpy)" in r.stderr
