"""examples/data_fitting: the lab reads its data file by name from any working directory and
fits it as SciPy does when called here on the same file; the fit finds the parameters the
data were made from (within three standard deviations); the replayed motion is the model's
closed form; the fit is printed."""

from __future__ import annotations

import csv
import io
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import curve_fit

from testkit import EXAMPLES

CSV = EXAMPLES / "data_fitting" / "measured.csv"
#: the values measured.csv was made from (its header says so)
TRUE = {"A": 1.0, "gamma": 0.35, "omega": 2 * math.pi * 0.8}


def _model(t, a, g, w):
    return a * np.exp(-g * t) * np.cos(w * t)


@pytest.fixture(scope="module")
def run(built, tmp_path_factory: pytest.TempPathFactory) -> tuple[subprocess.CompletedProcess[str], dict[str, np.ndarray]]:
    app = built("data_fitting")
    elsewhere = tmp_path_factory.mktemp("cwd")
    r = subprocess.run([sys.executable, str(app / "app.py"), "--headless", "--duration", "2", "--csv", "-", "--set", "autofit=true",
                        "--vars", "t,x,A,gamma,omega,dA,dgamma,domega,rms", "--every", "5"],
                       capture_output=True, text=True, timeout=300, cwd=elsewhere)
    assert r.returncode == 0, r.stderr
    lines = [ln for ln in r.stdout.splitlines() if not ln.startswith(("read ", "fit "))]
    rows = list(csv.DictReader(io.StringIO("\n".join(lines))))
    return r, {k: np.array([float(row[k]) for row in rows]) for k in rows[0]}


def test_the_fit_is_scipys_on_the_same_file_and_finds_the_true_values(run) -> None:
    _r, d = run
    data = np.loadtxt(CSV, delimiter=",")
    p, cov = curve_fit(_model, data[:, 0], data[:, 1], p0=[0.8, 0.2, 4.5])
    sigma = np.sqrt(np.diag(cov))
    for i, name in enumerate(("A", "gamma", "omega")):
        assert d[name][0] == pytest.approx(p[i], rel=1e-9)
        assert d["d" + name][0] == pytest.approx(sigma[i], rel=1e-6)
        assert abs(d[name][0] - TRUE[name]) < 3 * sigma[i], name
    resid = data[:, 1] - _model(data[:, 0], *p)
    assert d["rms"][0] == pytest.approx(np.sqrt(np.mean(resid**2)), rel=1e-9)
    assert d["rms"][0] == pytest.approx(0.02, rel=0.25)  # the noise the data were made with


def test_the_replay_is_the_models_closed_form(run) -> None:
    _r, d = run
    exact = _model(d["t"], d["A"][0], d["gamma"][0], d["omega"][0])
    assert np.max(np.abs(d["x"] - exact)) < 1e-5  # RK4 at dt = 0.02 s (omega dt = 0.1): a few micrometres in 2 s
    assert d["t"][-1] == pytest.approx(2.0)


def test_the_fit_is_printed(run) -> None:
    r, d = run
    printed = r.stdout.splitlines()
    assert printed[0] == "read 81 points from data_fitting/measured.csv, t = 0 to 8 s"
    assert printed[1] == (f"fit 1: A = {d['A'][0]:.4f} ± {d['dA'][0]:.4f} m, gamma = {d['gamma'][0]:.4f} ± {d['dgamma'][0]:.4f} 1/s, "
                          f"omega = {d['omega'][0]:.4f} ± {d['domega'][0]:.4f} rad/s")


def test_the_data_file_is_the_documented_damped_oscillator() -> None:
    data = np.loadtxt(CSV, delimiter=",")
    assert data.shape == (81, 2) and np.allclose(np.diff(data[:, 0]), 0.1)
    noise = data[:, 1] - _model(data[:, 0], TRUE["A"], TRUE["gamma"], TRUE["omega"])
    assert abs(noise.mean()) < 0.01 and 0.012 < noise.std() < 0.028
    assert "\r" not in Path(CSV).read_text()


def test_every_element_of_the_view_shows_without_an_error(built) -> None:
    """Labels, tables and plots are evaluated only in the browser: read each one as the panel does."""
    from ejsrl.app import load_app
    from ejsrl.view.elements import Dynamic

    app = load_app(built("data_fitting"))
    props = []
    for el in app.view:
        for sub in [el, *getattr(el, "rows", []), *getattr(el, "series", []), *getattr(el, "children", [])]:
            props += [v for v in vars(sub).values() if isinstance(v, Dynamic)]
    assert len(props) >= 12
    for prop in props:
        assert app.safe_value(prop) is not None, f"{prop}: {app.error}"
    assert app.error is None
    label = next(el for el in app.view if type(el).__name__ == "Label")
    assert f"| period 2π/ω | {2 * math.pi / 4.5:.4f} s |".replace(".", "&#46;") in app.safe_value(label.text)  # escaped
