"""ejsrl.vision: image functions over NumPy arrays, SUSAN, pipelines, the camera model and visual servoing.

Images are NumPy arrays, and every image function checks its input the same way:

- **Shape.** (H, W) grey, (H, W, 3) RGB or (H, W, 4) RGBA (the alpha is dropped); (H, W, 1)
  counts as grey. Any other shape, and an empty image (H or W of 0), is a ``ValueError``.
- **Channel order.** R, G, B (as the renderer and the browser give them; never OpenCV's BGR).
- **Values.** uint8 0..255 is the native type; the others are read as follows, and anything
  else (complex, strings, None) is a ``ValueError`` rather than a silent guess:

  - bool: a mask, False -> 0, True -> 255;
  - uint16: the full range 0..65535 scaled to 0..255 (``round(v / 257)``);
  - other integers (int32, int64: what Python ints give): must already lie in 0..255;
  - float16/32/64: must be finite (no NaN or inf) and lie in [0, 1] (scaled by 255); use
    ``normalize(img)`` for another range, ``img / 255`` for 0..255 values, ``np.nan_to_num``
    for NaN. Functions that compute in float (``log_filter``, ``gaussian_pyramid``,
    ``watershed``'s relief, ``hu_moments``) take finite floats in any range.

- **Options** given as strings ("mean", "orb", ...) are checked: an unknown one is a
  ``ValueError`` that lists the known ones (``feature_methods()`` lists the feature
  detectors this OpenCV has).

A bad input is a ``ValueError`` that says what to do, never an OpenCV error or a crash.
Features are ``(x, y)`` = (column, row) pixel coordinates, as in OpenCV. SUSAN corners run
compiled, about 3x faster than the NumPy path on one thread and outside the GIL, when numba is installed: ``pip install 'ejsgen[fast]'``
(the same corners either way; ``EJSRL_SUSAN=numpy`` forces the NumPy path). Everything public
is importable from here:

    from ejsrl.vision import Pipeline, susan, CameraModel, interaction_matrix, ibvs_velocity

Fiducial markers (``detect_markers``, ``marker_pose``; ``ejsrl.vision.markers``), point clouds
from depth images and ICP (``depth_to_points``, ``icp``; ``ejsrl.vision.pointcloud``) and real
image sources (``ImageSource``: a camera, a stream, a video or images; ``ejsrl.vision.sources``)
are here too.
"""

from __future__ import annotations

from ejsrl._lazy import lazy_exports
from ejsrl.vision import servo as _servo  # NumPy only, as the camera model it uses

# Each name is imported from its module when first read (ejsrl._lazy): the package imports without
# OpenCV (a browser's Python has none), and an app that uses none of these does not load it.
__getattr__, __dir__ = lazy_exports(__name__, {
    "._susan": ("SUSAN_MASK", "susan", "susan_corners", "susan_edges", "usan_area"),
    ".camera": ("CameraModel", "intrinsics_from_fov", "look_at", "pose_from_rvec"),
    ".colorspace": ("delta_e", "lab_to_rgb", "lab_to_xyz", "rgb_to_lab", "rgb_to_xyz", "xyz_to_lab", "xyz_to_rgb"),
    ".flow": ("flow_magnitude", "optical_flow", "warp_by_flow"),
    ".scale": (
        "collapse_laplacian_pyramid", "dog_filter", "gaussian_pyramid", "laplacian_pyramid", "log_blobs", "log_filter"
    ),
    ".segmentation": ("distance_transform", "skeleton", "split_touching", "watershed"),
    ".shape": ("ellipse_from_moments", "hu_moments"),
    ".matching": (
        "Features", "detect_features", "epipolar_distances", "feature_methods", "find_essential", "find_fundamental",
        "find_homography", "match_features", "recover_pose"
    ),
    ".stereo": ("StereoRectification", "depth_from_disparity", "disparity", "stereo_rectify", "triangulate"),
    ".calibration": (
        "Calibration", "calibrate_camera", "calibrate_chessboard", "chessboard_points", "draw_chessboard",
        "find_chessboard"
    ),
    ".color": (
        "adjust_brightness_contrast", "adjust_gamma", "clahe", "equalize_histogram", "histogram", "hsv_to_rgb",
        "invert", "normalize", "rgb_to_hsv", "threshold", "threshold_adaptive", "threshold_otsu", "to_gray", "to_rgb"
    ),
    ".draw": ("draw_boxes", "draw_circles", "draw_contours", "draw_lines", "draw_points", "draw_text"),
    ".edges": ("canny", "gradient_magnitude", "laplacian", "prewitt", "roberts", "scharr", "sobel"),
    ".features": (
        "Region", "blobs", "centroid", "color_mask", "color_segment", "connected_components", "fast_corners",
        "find_contours", "harris_corners", "harris_response", "hough_circles", "hough_lines", "hough_segments",
        "lk_track", "match_template", "moments", "orb_features", "shi_tomasi_corners"
    ),
    ".filters": (
        "add_gaussian_noise", "add_salt_pepper_noise", "bilateral_filter", "black_hat", "box_filter", "convolve",
        "dilate", "erode", "gaussian_blur", "median_blur", "morph_close", "morph_gradient", "morph_open", "sharpen",
        "structuring_element", "top_hat"
    ),
    ".geometry": (
        "affine_matrix", "crop", "flip", "perspective_matrix", "resize", "rotate", "warp_affine", "warp_perspective"
    ),
    ".pipeline": ("STEPS", "Pipeline", "PipelineResult"),
    ".markers": ("MARKER_DICTIONARIES", "Marker", "detect_markers", "marker_bits", "marker_image", "marker_pose"),
    ".pointcloud": (
        "IcpResult", "best_rigid_transform", "depth_to_points", "estimate_normals", "icp", "transform_points",
        "voxel_downsample"
    ),
    ".sources": ("ImageSource",),
    ".servo": (
        "ServoMonitor", "camera_twist_to_world", "eih_joint_velocities", "feature_error", "ibvs_velocity",
        "integrate_twist", "interaction_matrix", "match_points", "pbvs_velocity", "skew", "theta_u", "twist_transform"
    ),
})

#: the image functions (each takes and/or returns images), for documentation and counting
IMAGE_FUNCTIONS: tuple[str, ...] = (
    # conversions and thresholds
    "to_gray", "to_rgb", "rgb_to_hsv", "hsv_to_rgb", "threshold", "threshold_otsu", "threshold_adaptive", "invert",
    "normalize",
    # adjustment and histograms
    "adjust_brightness_contrast", "adjust_gamma", "equalize_histogram", "clahe", "histogram",
    # geometry
    "resize", "rotate", "flip", "crop", "warp_affine", "warp_perspective", "affine_matrix", "perspective_matrix",
    # filters and noise
    "box_filter", "gaussian_blur", "median_blur", "bilateral_filter", "sharpen", "convolve", "add_gaussian_noise",
    "add_salt_pepper_noise",
    # morphology
    "structuring_element", "erode", "dilate", "morph_open", "morph_close", "morph_gradient", "top_hat", "black_hat",
    # edges
    "sobel", "scharr", "prewitt", "roberts", "laplacian", "gradient_magnitude", "canny", "susan_edges",
    # point features
    "harris_response", "harris_corners", "shi_tomasi_corners", "fast_corners", "orb_features", "susan_corners",
    "usan_area", "susan",
    # lines, circles, regions
    "hough_lines", "hough_segments", "hough_circles", "connected_components", "find_contours", "moments", "centroid",
    "blobs", "color_mask", "color_segment",
    # matching and tracking
    "match_template", "lk_track",
    # drawing
    "draw_points", "draw_lines", "draw_boxes", "draw_circles", "draw_contours", "draw_text",
)  # fmt: skip

__all__ = [
    *IMAGE_FUNCTIONS,
    "IMAGE_FUNCTIONS",
    "SUSAN_MASK",
    "Region",
    "Pipeline",
    "PipelineResult",
    "STEPS",
    "CameraModel",
    "intrinsics_from_fov",
    "look_at",
    "pose_from_rvec",
    "rgb_to_xyz", "xyz_to_rgb", "xyz_to_lab", "lab_to_xyz", "rgb_to_lab", "lab_to_rgb", "delta_e",
    "optical_flow", "flow_magnitude", "warp_by_flow",
    "gaussian_pyramid", "laplacian_pyramid", "collapse_laplacian_pyramid", "log_filter", "dog_filter", "log_blobs",
    "distance_transform", "watershed", "split_touching", "skeleton",
    "hu_moments", "ellipse_from_moments",
    "Features", "detect_features", "feature_methods", "match_features", "find_homography", "find_fundamental", "find_essential",
    "recover_pose", "epipolar_distances",
    "StereoRectification", "stereo_rectify", "disparity", "depth_from_disparity", "triangulate",
    "Calibration", "calibrate_camera", "calibrate_chessboard", "chessboard_points", "draw_chessboard", "find_chessboard",
    "interaction_matrix", "ibvs_velocity", "feature_error", "skew", "twist_transform",
    "camera_twist_to_world", "eih_joint_velocities", "integrate_twist", "match_points", "theta_u", "pbvs_velocity", "ServoMonitor",
    "MARKER_DICTIONARIES", "Marker", "detect_markers", "marker_bits", "marker_image", "marker_pose",
    "IcpResult", "best_rigid_transform", "depth_to_points", "estimate_normals", "icp", "transform_points", "voxel_downsample",
    "ImageSource",
]
