"""Write the VRML97 link meshes of the six-axis arm example (run once; the .wrl files are committed).

Each file holds one link in that link's own frame (standard Denavit-Hartenberg frame i
for link i, link 0 being the base), built from VRML primitives: the body that joins the
previous joint to this one, and the housing of the next joint. The DH table is the one
of ``../six_axis_arm.ejs.yaml`` (the EjsRL paper's arm, figure 4):

    link   d     a     alpha
    1      L1    0     -pi/2     L1 = 0.45 m (shoulder height)
    2      0     A2    0         A2 = 0.40 m (upper arm)
    3      0     0     +pi/2
    4      L4    0     -pi/2     L4 = 0.40 m (forearm)
    5      0     0     +pi/2
    6      L6    0     0         L6 = 0.10 m (wrist to tool tip)

In frame i, link i's body runs from the origin of frame i-1, at
(-a, -d sin(alpha), -d cos(alpha)), to the origin. VRML cylinders stand along their
local y axis, so each one gets a rotation that lays y along the wanted axis.

    python examples/six_axis_arm/make_meshes.py [OUTPUT_FOLDER]
"""

from __future__ import annotations

import sys
from pathlib import Path

L1, A2, L4, L6 = 0.45, 0.40, 0.40, 0.10

ORANGE = "0.91 0.54 0.17"
DARK = "0.24 0.25 0.28"
STEEL = "0.70 0.72 0.75"

#: VRML rotations (axis x y z, angle) that take a cylinder's y axis to x, y or z
ALONG = {"x": "0 0 1 -1.5708", "y": "0 1 0 0", "z": "1 0 0 1.5708"}


def shape(geometry: str, color: str, translation: tuple[float, float, float] = (0, 0, 0), axis: str = "y") -> str:
    t = " ".join(f"{v:g}" for v in translation)
    return (
        f"Transform {{ translation {t} rotation {ALONG[axis]} children [\n"
        f"  Shape {{ appearance Appearance {{ material Material {{ diffuseColor {color} }} }}\n"
        f"          geometry {geometry} }}\n"
        f"] }}\n"
    )


def cylinder(radius: float, height: float) -> str:
    return f"Cylinder {{ radius {radius:g} height {height:g} }}"


def box(x: float, y: float, z: float) -> str:
    return f"Box {{ size {x:g} {y:g} {z:g} }}"


LINKS = {
    # base: a pedestal on the floor and the waist motor (joint 1 turns about z0)
    0: [
        shape(cylinder(0.15, 0.05), DARK, (0, 0, 0.025), "z"),
        shape(cylinder(0.10, 0.12), DARK, (0, 0, 0.11), "z"),
    ],
    # waist: the column from the top of the base (y1 = L1 - 0.17; the floor is at y1 = +L1)
    # up to the shoulder, and the shoulder motor on z1 (joint 2)
    1: [
        shape(cylinder(0.08, L1 - 0.21), ORANGE, (0, (L1 - 0.11) / 2, 0), "y"),
        shape(cylinder(0.085, 0.20), DARK, (0, 0, 0), "z"),
    ],
    # upper arm: a beam along x2 from the shoulder (x2 = -A2) to the elbow motor on z2 (joint 3)
    2: [
        shape(box(A2 - 0.10, 0.10, 0.08), ORANGE, (-A2 / 2, 0, 0.14), "y"),
        shape(cylinder(0.07, 0.10), ORANGE, (-A2, 0, 0.14), "z"),
        shape(cylinder(0.07, 0.10), ORANGE, (0, 0, 0.14), "z"),
        shape(cylinder(0.065, 0.16), DARK, (0, 0, 0.04), "z"),
    ],
    # elbow: the root of the forearm along z3 (joint 4 rolls the rest of the forearm about it)
    3: [
        shape(cylinder(0.06, 0.14), ORANGE, (0, 0, 0.07), "z"),
        shape(cylinder(0.056, 0.012), DARK, (0, 0, 0.146), "z"),
    ],
    # forearm: from its root (y4 = L4 - 0.14; the elbow is at y4 = +L4) to the wrist motor on z4 (joint 5)
    4: [
        shape(cylinder(0.05, L4 - 0.205), ORANGE, (0, (0.065 + L4 - 0.14) / 2, 0), "y"),
        shape(cylinder(0.055, 0.13), DARK, (0, 0, 0), "z"),
    ],
    # wrist: the short housing of joint 6 along z5
    5: [
        shape(cylinder(0.045, 0.06), DARK, (0, 0, 0.03), "z"),
    ],
    # flange and a two-finger gripper; the tool point (frame 6's origin) is between the finger tips
    6: [
        shape(cylinder(0.045, 0.015), STEEL, (0, 0, -L6 + 0.0675), "z"),
        shape(box(0.03, 0.11, 0.02), STEEL, (0, 0, -0.04), "y"),
        shape(box(0.02, 0.012, 0.05), DARK, (0, 0.045, -0.005), "y"),
        shape(box(0.02, 0.012, 0.05), DARK, (0, -0.045, -0.005), "y"),
    ],
}


def main(out: Path | None = None) -> None:
    """Write link0.wrl ... link6.wrl into ``out`` (default: this script's folder)."""
    here = Path(__file__).resolve().parent if out is None else Path(out)
    for i, shapes in LINKS.items():
        text = (
            "#VRML V2.0 utf8\n"
            f"# Six-axis arm, link {i}{' (base)' if i == 0 else ''}, in its Denavit-Hartenberg frame {i}.\n"
            "# Written by make_meshes.py; metres.\n"
            + "".join(shapes)
        )
        (here / f"link{i}.wrl").write_text(text)


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else None)
