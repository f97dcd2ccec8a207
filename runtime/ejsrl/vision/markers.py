"""Fiducial markers: ArUco and AprilTag detection, pose, and the marker images themselves.

OpenCV's ``cv2.aruco`` does the work (opencv-python-headless has it); the dictionaries are
named here in lower case:

- ArUco: ``"aruco_4x4_50"``, ``"aruco_4x4_100"``, ... ``"aruco_7x7_1000"`` (4..7 bits a
  side, 50/100/250/1000 markers), ``"aruco_original"`` (5x5, 1024 markers) and
  ``"aruco_mip_36h12"``;
- AprilTag (the families OpenCV has): ``"apriltag_16h5"``, ``"apriltag_25h9"``,
  ``"apriltag_36h10"``, ``"apriltag_36h11"``.

A marker is a square of ``n x n`` data cells inside a one-cell black border; it needs a
light quiet zone around it (at least one cell) to be found. Corners are ``(x, y)`` pixels
in OpenCV's order: the marker's top-left, top-right, bottom-right, bottom-left (as the
marker image is drawn), refined to sub-pixel accuracy. The marker's own frame (for
``marker_pose``): origin at its centre, x towards its right edge, y towards its top edge, z
out of its face (towards a camera that sees it); its side is ``side`` metres, the black
border included.

The virtual camera draws a marker on a solid element whose ``texture`` is
``"<dictionary>:<id>"`` (e.g. ``"aruco_4x4_50:7"``) and whose ``texture_size`` is the
marker's side in metres: on the faces that look along the element's +z axis, centred on
its origin, read the right way up when seen from +z with the element's y axis up.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision._util import as_gray, choice

__all__ = [
    "MARKER_DICTIONARIES", "Marker", "detect_markers", "marker_bits", "marker_image", "marker_pose", "marker_corners_3d",
    "parse_marker_texture",
]

#: the dictionaries by their names here -> OpenCV's constant
MARKER_DICTIONARIES: dict[str, int] = {
    **{f"aruco_{n}x{n}_{k}": getattr(cv2.aruco, f"DICT_{n}X{n}_{k}") for n in (4, 5, 6, 7) for k in (50, 100, 250, 1000)},
    "aruco_original": cv2.aruco.DICT_ARUCO_ORIGINAL,
    "aruco_mip_36h12": cv2.aruco.DICT_ARUCO_MIP_36h12,
    "apriltag_16h5": cv2.aruco.DICT_APRILTAG_16h5,
    "apriltag_25h9": cv2.aruco.DICT_APRILTAG_25h9,
    "apriltag_36h10": cv2.aruco.DICT_APRILTAG_36h10,
    "apriltag_36h11": cv2.aruco.DICT_APRILTAG_36h11,
}


@functools.lru_cache(maxsize=None)
def _dictionary(name: str) -> Any:
    return cv2.aruco.getPredefinedDictionary(MARKER_DICTIONARIES[choice(name, MARKER_DICTIONARIES, "marker dictionary")])


def _size(name: str) -> int:
    """How many markers the dictionary ``name`` has."""
    return int(_dictionary(name).bytesList.shape[0])


def _check_id(dictionary: str, marker_id: Any) -> int:
    if isinstance(marker_id, bool) or not isinstance(marker_id, (int, np.integer)):
        raise ValueError(f"a marker id is a whole number, got {marker_id!r}")
    n = _size(dictionary)
    if not 0 <= int(marker_id) < n:
        raise ValueError(f"marker id {int(marker_id)} is not in {dictionary!r}, which has ids 0..{n - 1}")
    return int(marker_id)


@functools.lru_cache(maxsize=256)
def _bits(dictionary: str, marker_id: int) -> NDArray[np.bool_]:
    d = _dictionary(dictionary)
    n = int(d.markerSize)
    img = cv2.aruco.generateImageMarker(d, marker_id, n + 2, borderBits=1)  # one pixel a cell
    out = img < 128
    out.setflags(write=False)
    return out


def marker_bits(dictionary: str, marker_id: int) -> NDArray[np.bool_]:
    """The marker's cells (n + 2, n + 2) bool, True = black, the one-cell black border included;
    row 0 is the marker's top edge, column 0 its left edge."""
    return np.array(_bits(choice(dictionary, MARKER_DICTIONARIES, "marker dictionary"), _check_id(dictionary, marker_id)))


def marker_image(dictionary: str, marker_id: int, side_px: int = 240, *, quiet_zone: int = 1) -> NDArray[np.uint8]:
    """A printable marker: grey uint8 image, ``side_px`` pixels the marker (border included)
    plus ``quiet_zone`` white cells around it (a detector needs at least one)."""
    bits = marker_bits(dictionary, marker_id)
    cells = bits.shape[0]
    side_px = int(side_px)
    if side_px < cells:
        raise ValueError(f"side_px must be at least {cells} (one pixel a cell), got {side_px}")
    if int(quiet_zone) < 0:
        raise ValueError(f"quiet_zone is a number of cells >= 0, got {quiet_zone}")
    idx = (np.arange(side_px) * cells) // side_px
    core = np.where(bits[np.ix_(idx, idx)], 0, 255).astype(np.uint8)
    pad = int(round(quiet_zone * side_px / cells))
    return np.pad(core, pad, constant_values=255)


def parse_marker_texture(texture: str) -> tuple[str, int] | None:
    """``"aruco_4x4_50:7"`` -> ``("aruco_4x4_50", 7)``; None when ``texture`` names no dictionary;
    a ValueError (with the known dictionaries, or the id range) when it is a marker texture gone wrong."""
    if not isinstance(texture, str) or ":" not in texture:
        return None
    name, _, ident = texture.partition(":")
    name = name.strip().lower()
    if not (name.startswith("aruco") or name.startswith("apriltag")):
        return None
    choice(name, MARKER_DICTIONARIES, "marker dictionary")
    try:
        marker_id = int(ident.strip())
    except ValueError:
        raise ValueError(f"marker texture {texture!r}: after the ':' comes the marker's id, a whole number") from None
    return name, _check_id(name, marker_id)


@dataclass(frozen=True)
class Marker:
    """A marker found in an image: its ``id`` and its ``corners`` (4, 2) pixels (x, y), in the
    order top-left, top-right, bottom-right, bottom-left of the marker."""

    id: int
    corners: NDArray[np.float64]

    @property
    def center(self) -> NDArray[np.float64]:
        """Where its diagonals cross, (x, y) pixels."""
        p = self.corners
        a, b = p[0], p[2]
        c, d = p[1], p[3]
        m = np.array([[b[0] - a[0], c[0] - d[0]], [b[1] - a[1], c[1] - d[1]]])
        try:
            s = np.linalg.solve(m, c - a)[0]
        except np.linalg.LinAlgError:
            return p.mean(axis=0)
        return a + s * (b - a)

    def pose(self, side: float, camera: Any, previous: ArrayLike | None = None) -> NDArray[np.float64]:
        """``T_camera_marker`` (4, 4) for a marker of side ``side`` metres (``marker_pose``)."""
        return marker_pose(self.corners, side, camera, previous=previous)


def detect_markers(img: ArrayLike, dictionary: str = "aruco_4x4_50", *, refine: bool = True) -> list[Marker]:
    """The markers of ``dictionary`` in ``img`` (grey or RGB), sorted by id.

    ``refine``: corners to sub-pixel accuracy (OpenCV's ``CORNER_REFINE_SUBPIX``). A marker
    seen twice is listed twice.
    """
    gray = as_gray(img)
    params = cv2.aruco.DetectorParameters()
    if refine:
        params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    det = cv2.aruco.ArucoDetector(_dictionary(choice(dictionary, MARKER_DICTIONARIES, "marker dictionary")), params)
    corners, ids, _rejected = det.detectMarkers(gray)
    if ids is None:
        return []
    out = [Marker(int(i), np.asarray(c, dtype=np.float64).reshape(4, 2)) for c, i in zip(corners, ids.reshape(-1))]
    return sorted(out, key=lambda m: (m.id, float(m.corners[0, 1]), float(m.corners[0, 0])))


def marker_corners_3d(side: float) -> NDArray[np.float64]:
    """The marker's corners (4, 3) in its own frame, in the detector's order (metres)."""
    h = float(side) / 2.0
    return np.array([[-h, h, 0.0], [h, h, 0.0], [h, -h, 0.0], [-h, -h, 0.0]])


def _T(rvec: Any, tvec: Any) -> NDArray[np.float64]:
    R, _ = cv2.Rodrigues(np.asarray(rvec, dtype=np.float64))
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = np.asarray(tvec, dtype=np.float64).reshape(3)
    return T


def _angle(Ra: NDArray[np.float64], Rb: NDArray[np.float64]) -> float:
    return float(np.arccos(np.clip((np.trace(Ra.T @ Rb) - 1.0) / 2.0, -1.0, 1.0)))


def marker_pose(corners: ArrayLike, side: float, camera: Any, *, previous: ArrayLike | None = None) -> NDArray[np.float64]:
    """``T_camera_marker`` (4, 4): the marker's pose in the camera frame from its 4 corners.

    ``corners`` (4, 2): as ``detect_markers`` gives them; ``side``: the marker's side in
    metres (border included); ``camera``: a ``CameraModel`` (its K and distortion are
    used). Candidates: OpenCV's planar ``SOLVEPNP_IPPE`` (its two solutions: mirror tilts
    that fit the corners almost equally well when the marker is seen nearly square-on or
    small) and ``SOLVEPNP_SQPNP``, each refined by Levenberg-Marquardt; the one with the
    smallest reprojection error is kept. (``SOLVEPNP_IPPE_SQUARE`` alone fails on a square
    seen exactly square-on: it returns no rotation and a 90 px error.) ``previous`` (4, 4):
    the pose of the last frame; then, of the candidates that fit to within 0.5 px (or twice
    the best error), the one turned least from it is kept, so a tracked marker does not
    flip from frame to frame.
    """
    side = float(side)
    if not (np.isfinite(side) and side > 0):
        raise ValueError(f"side is the marker's side in metres (> 0), got {side!r}")
    px = np.asarray(corners, dtype=np.float64).reshape(-1, 2)
    if px.shape != (4, 2) or not np.all(np.isfinite(px)):
        raise ValueError(f"corners must be the marker's 4 finite (x, y) corners, got shape {px.shape}")
    P = marker_corners_3d(side)
    K = np.asarray(camera.K, dtype=np.float64)
    dist = np.asarray(getattr(camera, "distortion", np.zeros(5)), dtype=np.float64)
    cands: list[tuple[float, NDArray[np.float64]]] = []
    for flag in (cv2.SOLVEPNP_IPPE, cv2.SOLVEPNP_SQPNP):
        try:
            n, rvecs, tvecs, _ = cv2.solvePnPGeneric(P, px, K, dist, flags=flag)
        except cv2.error:
            continue
        for i in range(int(n)):
            rvec, tvec = cv2.solvePnPRefineLM(P, px, K, dist, rvecs[i], tvecs[i])
            proj, _ = cv2.projectPoints(P, rvec, tvec, K, dist)
            err = float(np.sqrt(np.mean(np.sum((proj.reshape(-1, 2) - px) ** 2, axis=1))))
            T = _T(rvec, tvec)
            if np.isfinite(err) and np.all(np.isfinite(T)) and T[2, 3] > 0:
                cands.append((err, T))
    if not cands:
        raise ValueError("no pose fits these corners (is the quadrilateral degenerate?)")
    best_err = min(e for e, _ in cands)
    if previous is not None:
        Tp = np.asarray(previous, dtype=np.float64).reshape(4, 4)
        if np.all(np.isfinite(Tp)):
            fits = [T for e, T in cands if e <= max(0.5, 2.0 * best_err)]
            return min(fits, key=lambda T: _angle(T[:3, :3], Tp[:3, :3]))
    return min(cands, key=lambda c: c[0])[1]
