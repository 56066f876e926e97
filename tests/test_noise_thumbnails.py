"""Depth noise model statistics and grasp-thumbnail geometry on synthetic images with known answers."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch
from scipy import ndimage, stats

from suctionbench.errors import InputError
from suctionbench.sensing.camera import PRIMESENSE
from suctionbench.sensing.image import save_png
from suctionbench.sensing.noise import (
    DEPTH_NOISE_PAPER,
    DepthNoiseConfig,
    _gp_operator,
    apply_depth_noise,
    apply_depth_noise_torch,
    gp_field_std,
    sample_gamma,
    sample_gamma_torch,
    sample_gp_field,
)
from suctionbench.sensing.thumbnails import (
    THUMBNAIL_CONTEXT,
    THUMBNAIL_GQCNN,
    ThumbnailConfig,
    affine_sample,
    bilinear_sample,
    extract_context_thumbnails,
    extract_thumbnails,
    extract_thumbnails_reference,
    pose_vector,
    project_grasps,
    sample_thumbnails,
    to_uint8_grid,
    visible_mask,
)

K = PRIMESENSE
PLANE = 0.6
ALPHA_STD = math.sqrt(1000.0) * 0.001


# --------------------------------------------------------------------------------------------------
# Noise
# --------------------------------------------------------------------------------------------------


def _check_alpha(samples: np.ndarray, mean: float, std: float) -> None:
    n = len(samples)
    assert abs(samples.mean() - mean) < 5 * std / math.sqrt(n)
    assert abs(samples.std() / std - 1.0) < 5 / math.sqrt(2 * n)


def test_gamma_mean_one_and_std_matches_shape():
    rng = np.random.default_rng(0)
    alpha = sample_gamma(rng, size=40_000)
    _check_alpha(alpha, 1.0, ALPHA_STD)
    assert isinstance(sample_gamma(rng), float)


def test_torch_gamma_sampler_is_the_gamma_distribution():
    alpha = sample_gamma_torch(40_000, torch.Generator().manual_seed(0)).numpy()
    _check_alpha(alpha, 1.0, ALPHA_STD)
    assert stats.kstest(alpha, "gamma", args=(1000.0, 0.0, 0.001)).pvalue > 1e-3
    again = sample_gamma_torch(40_000, torch.Generator().manual_seed(0)).numpy()
    np.testing.assert_array_equal(alpha, again)
    # shape < 1 takes the boosted path: Gamma(0.5, 2) has mean 1 and std sqrt(2)
    small = sample_gamma_torch(40_000, torch.Generator().manual_seed(1), DepthNoiseConfig(0.5, 2.0)).numpy()
    _check_alpha(small, 1.0, math.sqrt(2.0))


def test_gp_field_std_is_the_derived_fraction_of_sigma():
    # Derivation (noise.py docstring): image-average std = mean of the summed squared Keys weights
    # over the pixel phases = 0.814 sigma for white coarse samples; 0.819 with the paper's bandwidth.
    assert gp_field_std(480, 640, DepthNoiseConfig(gp_bandwidth_px=0.0)) / 0.005 == pytest.approx(0.8140, abs=5e-4)
    expected = gp_field_std(64, 64)
    assert expected / 0.005 == pytest.approx(0.819, abs=2e-3)
    rng = np.random.default_rng(1)
    fields = np.stack([sample_gp_field(rng, 64, 64) for _ in range(300)])
    assert fields.dtype == np.float32 and fields.shape == (300, 64, 64)
    assert math.sqrt(np.mean(fields.astype(float) ** 2)) == pytest.approx(expected, rel=0.02)
    assert abs(fields.mean()) < 0.02 * 0.005


def _row_autocorrelation(fields: np.ndarray, max_lag: int) -> np.ndarray:
    f = fields.astype(float)
    var = np.mean(f * f)
    return np.array([1.0] + [np.mean(f[..., :-k] * f[..., k:]) / var for k in range(1, max_lag + 1)])


def _half_width(corr: np.ndarray) -> float:
    j = int(np.argmax(corr < 0.5))
    return j - 1 + (corr[j - 1] - 0.5) / (corr[j - 1] - corr[j])


def test_gp_correlation_length_follows_rescale_factor():
    rng = np.random.default_rng(2)
    widths = {}
    for r in (4.0, 8.0):
        config = DepthNoiseConfig(gp_rescale_factor=r)
        fields = np.stack([sample_gp_field(rng, 32, 128, config) for _ in range(200)])
        measured = _row_autocorrelation(fields, 16)
        # exact expectation of the same estimator: the row factor cancels, leaving the column operator's
        m = _gp_operator(128, r, config.gp_bandwidth_px)
        cov = m @ m.T
        exact = np.array([np.mean(np.diagonal(cov, k)) for k in range(17)]) / np.mean(np.diagonal(cov))
        np.testing.assert_allclose(measured, exact, atol=0.03)
        assert measured[1] > 0.9 and abs(measured[int(2 * r)]) < 0.1  # smooth below r, uncorrelated at 2r
        widths[r] = _half_width(measured)
    assert widths[4.0] == pytest.approx(0.68 * 4.0, rel=0.05)
    assert widths[8.0] / widths[4.0] == pytest.approx(2.0, rel=0.05)


def test_apply_depth_noise_is_alpha_times_depth_plus_field_and_keeps_zeros():
    depth = np.full((48, 64), PLANE, dtype=np.float32)
    depth[:10, :20] = 0.0
    noisy = apply_depth_noise(depth, np.random.default_rng(7))
    assert noisy.dtype == np.float32 and noisy.shape == depth.shape
    assert np.all(noisy[:10, :20] == 0.0) and np.all(noisy[depth > 0] > 0)
    replay = np.random.default_rng(7)
    alpha = sample_gamma(replay)
    field = sample_gp_field(replay, 48, 64)
    valid = depth > 0
    np.testing.assert_allclose(noisy[valid], (alpha * depth + field)[valid], rtol=1e-6)
    np.testing.assert_array_equal(noisy, apply_depth_noise(depth, np.random.default_rng(7)))
    assert not np.array_equal(noisy, apply_depth_noise(depth, np.random.default_rng(8)))


def test_torch_noise_per_sample_probability_zeros_and_determinism():
    images = torch.full((200, 1, 32, 32), PLANE)
    images[:, :, :4, :] = 0.0
    out = apply_depth_noise_torch(images, torch.Generator().manual_seed(3), prob=0.5)
    assert out.shape == images.shape and out.dtype == images.dtype
    assert torch.all(out[:, :, :4, :] == 0.0)
    changed = (out != images).flatten(1).any(dim=1)
    assert 0.35 < changed.float().mean().item() < 0.65
    assert torch.all((out[changed] != images[changed])[:, :, 4:, :])  # a noised sample is noised everywhere valid
    again = apply_depth_noise_torch(images, torch.Generator().manual_seed(3), prob=0.5)
    assert torch.equal(out, again)
    assert torch.equal(apply_depth_noise_torch(images, torch.Generator().manual_seed(3), prob=0.0), images)

    # Gamma only: each sample is its own constant multiple of the input.
    scaled = apply_depth_noise_torch(images, torch.Generator().manual_seed(4), gp_prob=0.0)
    ratio = (scaled[:, :, 4:, :] / images[:, :, 4:, :]).flatten(1)
    assert torch.allclose(ratio, ratio[:, :1].expand_as(ratio))
    _check_alpha(ratio[:, 0].double().numpy(), 1.0, ALPHA_STD)

    # Field only (alpha pinned to 1): per-pixel std as derived for a 32 x 32 image.
    no_gamma = DepthNoiseConfig(gamma_shape=1e12, gamma_scale=1e-12)
    field = apply_depth_noise_torch(images, torch.Generator().manual_seed(5), no_gamma) - images
    assert field[:, :, 4:, :].double().pow(2).mean().sqrt().item() == pytest.approx(
        gp_field_std(32, 32, no_gamma), rel=0.05
    )


def test_noise_config_rejects_nonsense():
    with pytest.raises(ValueError, match="gp_rescale_factor"):
        DepthNoiseConfig(gp_rescale_factor=0.5)
    with pytest.raises(ValueError, match="gamma_shape"):
        DepthNoiseConfig(gamma_shape=0.0)
    assert DEPTH_NOISE_PAPER.gp_bandwidth_px == pytest.approx(math.sqrt(2.0))


# --------------------------------------------------------------------------------------------------
# Thumbnails
# --------------------------------------------------------------------------------------------------


def _point(u: float, v: float, z: float) -> np.ndarray:
    """Camera-frame point that projects to pixel (u, v) at z-depth z."""
    return np.array([(u - K.cx) * z / K.fx, (v - K.cy) * z / K.fy, z])


def _unit(x) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    return x / np.linalg.norm(x)


def _plane() -> np.ndarray:
    return np.full((K.height, K.width), PLANE, dtype=np.float32)


def _centroid(thumb: np.ndarray) -> np.ndarray:
    """(row, col) centroid of the height of the thumbnail above the plane."""
    w = np.clip(PLANE - thumb.astype(float), 0.0, None)
    rows, cols = np.indices(thumb.shape)
    return np.array([(w * rows).sum(), (w * cols).sum()]) / w.sum()


def test_project_grasps_agrees_with_camera_projection():
    rng = np.random.default_rng(3)
    points = np.column_stack([rng.uniform(-0.2, 0.2, (50, 2)), rng.uniform(0.4, 0.8, 50)])
    approaches = rng.normal(size=(50, 3)) + [0.0, 0.0, 1.5]
    approaches /= np.linalg.norm(approaches, axis=1, keepdims=True)
    pixels, depths, angles = project_grasps(points, approaches, K)
    np.testing.assert_allclose(pixels, K.project(points))
    np.testing.assert_array_equal(depths, points[:, 2])
    for s in (1e-6, 0.05):  # the image of p + s v lies on the ray from the grasp pixel at the angle
        step = K.project(points + s * approaches) - pixels
        along = step[:, 0] * np.cos(angles) + step[:, 1] * np.sin(angles)
        across = -step[:, 0] * np.sin(angles) + step[:, 1] * np.cos(angles)
        assert np.all(along > 0)
        np.testing.assert_allclose(across / along, 0.0, atol=1e-6)


def test_bump_lands_at_centre_and_approach_points_down_the_middle_column():
    u0, v0 = 400.0, 200.0
    top = 0.58
    p = _point(u0, v0, top)
    approach = _unit([0.5, -0.3, 1.0])  # oblique: its image points up and to the right
    pixels, depths, angles = project_grasps(p[None], approach[None], K)
    np.testing.assert_allclose(pixels[0], [u0, v0], atol=1e-9)

    bump = _plane()
    bump[196:205, 396:405] = top  # 9 x 9 px square centred on the grasp pixel
    thumb = extract_thumbnails(bump, pixels, angles)
    assert thumb.shape == (1, 32, 32) and thumb.dtype == np.float32
    np.testing.assert_allclose(_centroid(thumb[0]), [15.5, 15.5], atol=1e-6)
    assert visible_mask(pixels, depths, bump).tolist() == [True]

    # A smooth marker at the image of a later point on the approach ray lands straight below the centre.
    q = K.project(p + 0.12 * approach)
    distance = np.linalg.norm(q - pixels[0])
    assert 25 < distance < 45
    cols, rows = np.meshgrid(np.arange(K.width), np.arange(K.height))
    marker = _plane() - 0.03 * np.exp(-((cols - q[0]) ** 2 + (rows - q[1]) ** 2) / (2 * 4.0**2)).astype(np.float32)
    row, col = _centroid(extract_thumbnails(marker, pixels, angles)[0])
    assert col == pytest.approx(15.5, abs=0.05)
    assert row == pytest.approx(15.5 + distance / 3.0, abs=0.1)

    np.testing.assert_allclose(thumb, extract_thumbnails_reference(bump, pixels, angles), atol=1e-6)


def test_turning_the_approach_turns_the_thumbnail():
    rng = np.random.default_rng(4)
    image = PLANE + sample_gp_field(rng, K.height, K.width, DepthNoiseConfig(gp_sigma=0.01, gp_rescale_factor=8))
    p = _point(K.cx, K.cy, PLANE)  # on the optical axis, a turn about it turns the image direction
    approach = _unit([0.3, 0.1, 1.0])
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # +90 deg about the optical axis
    approaches = np.stack([approach, turn @ approach, turn @ turn @ approach])
    pixels, _, angles = project_grasps(np.stack([p] * 3), approaches, K)
    # +90 deg about z turns x (right) into y (down): clockwise on screen, +pi/2 in image angle
    np.testing.assert_allclose(np.angle(np.exp(1j * (angles[1:] - angles[0]))), [math.pi / 2, -math.pi], atol=1e-9)
    thumbs = extract_thumbnails(image, pixels, angles)
    assert thumbs[0].std() > 1e-3  # the pattern is not symmetric
    np.testing.assert_allclose(thumbs[1], np.rot90(thumbs[0], 1), atol=1e-6)  # content turns anticlockwise
    np.testing.assert_allclose(thumbs[2], np.rot90(thumbs[0], 2), atol=1e-6)


def test_bilinear_sample_is_scipys_order_1_nearest_interpolation():
    # Bilinear interpolation with the edge pixels repeated outside (scipy's map_coordinates, order 1,
    # mode "nearest") at points inside, on the border, on pixel centres and well outside the image;
    # both compute in float64 and round once to float32, so they agree to a float32 ulp.
    rng = np.random.default_rng(11)
    image = (0.6 + 0.1 * rng.random((37, 53))).astype(np.float32)
    rows = np.concatenate([rng.uniform(-6, 42, 500), [0.0, 36.0, 36.0, -1.0, 17.0]])
    cols = np.concatenate([rng.uniform(-6, 58, 500), [0.0, 52.0, -3.0, 60.0, 23.0]])
    want = ndimage.map_coordinates(image, [rows, cols], order=1, mode="nearest")
    got = bilinear_sample(image, rows.reshape(5, 101), cols.reshape(5, 101))
    assert got.dtype == np.float32 and got.shape == (5, 101)
    np.testing.assert_allclose(got.ravel(), want, rtol=2e-7, atol=0)
    assert got.ravel()[-1] == image[17, 23]  # a pixel centre is the pixel


def test_affine_lattices_sample_as_their_points_do():
    # Lattice k's sample (a, b) at origin_k + a down_k + b right_k: the same value bilinear_sample
    # gives at that point, for turned lattices inside the image and one running off two edges.
    rng = np.random.default_rng(12)
    image = (0.6 + 0.1 * rng.random((60, 80))).astype(np.float32)
    turn = np.append(rng.uniform(-math.pi, math.pi, 2), math.pi / 2 + 0.3)  # the last one runs down the image
    down = 1.5 * np.column_stack([np.cos(turn), np.sin(turn)])
    right = 1.5 * np.column_stack([np.sin(turn), -np.cos(turn)])
    origin = np.array([[30.2, 20.7], [41.0, 33.3], [-4.4, 55.1]])
    got = affine_sample(image, origin, down, right, (9, 13))
    a, b = np.mgrid[:9, :13]
    points = origin[:, None, None] + a[..., None] * down[:, None, None] + b[..., None] * right[:, None, None]
    assert (points < 0).any() and (points[..., 1] > 59).any()  # past the left and bottom edges
    want = bilinear_sample(image, points[..., 1], points[..., 0])
    assert got.shape == (3, 9, 13) and got.dtype == np.float32
    np.testing.assert_allclose(got, want, rtol=2e-7, atol=0)


def test_vectorised_extraction_matches_per_grasp_reference():
    rng = np.random.default_rng(5)
    image = PLANE + sample_gp_field(rng, 120, 160, DepthNoiseConfig(gp_sigma=0.01))
    pixels = rng.uniform([-10, -10], [170, 130], (40, 2))  # some crops leave the image: edge replication
    angles = rng.uniform(-math.pi, math.pi, 40)
    pixels[3] = np.nan
    thumbs = extract_thumbnails(image, pixels, angles)
    np.testing.assert_allclose(thumbs, extract_thumbnails_reference(image, pixels, angles), atol=1e-6)
    assert np.all(thumbs[3] == 0.0)


def test_context_thumbnail_sees_three_times_as_far_and_averages_its_blocks():
    # A box 60 px long lying with its near end 60 px beyond the grasp pixel along the approach's
    # image direction: outside the 96 px grasp crop (which reaches 46.5 px down its middle
    # column), inside the 288 px context crop (139.5 px). The context pixel is the mean of its 9 x 9 block: on a 1-pixel
    # checkerboard of +-1 mm, a block of 81 pixels averages to +-1/81 mm, against +-1 mm for
    # point samples.
    assert THUMBNAIL_CONTEXT.crop_size == 3 * THUMBNAIL_GQCNN.crop_size
    assert THUMBNAIL_CONTEXT.out_size == THUMBNAIL_GQCNN.out_size
    image = _plane()
    u0, v0 = 320.0, 200.0
    image[int(v0) + 60 : int(v0) + 120, 300:341] = PLANE - 0.05  # the box, straight down the image
    pixels, angles = np.array([[u0, v0]]), np.array([math.pi / 2])  # approach points down the image
    local = extract_thumbnails(image, pixels, angles)[0]
    context = extract_context_thumbnails(image, pixels, angles)[0]
    assert local.min() == pytest.approx(PLANE)  # the grasp crop does not see the box
    assert context.min() == pytest.approx(PLANE - 0.05, abs=1e-6)  # the context crop does
    rows = np.flatnonzero(context.min(axis=1) < PLANE - 0.025)
    step = THUMBNAIL_CONTEXT.crop_size / THUMBNAIL_CONTEXT.out_size  # 9 image pixels per pixel
    centre = THUMBNAIL_CONTEXT.centre
    assert rows.min() == pytest.approx(centre + 60 / step, abs=1.0)  # below the centre, 60 px away
    assert rows.max() == pytest.approx(centre + 120 / step, abs=1.0)
    checker = PLANE + 0.001 * np.where((np.add.outer(np.arange(K.height), np.arange(K.width)) % 2) == 0, 1.0, -1.0)
    smooth = extract_context_thumbnails(checker.astype(np.float32), pixels + 0.0, angles)[0]
    assert np.abs(smooth - PLANE).max() <= 0.001 / 81 + 1e-6


def test_visibility_accepts_the_surface_and_rejects_occluded_or_outside_points():
    image = _plane()
    image[196:205, 396:405] = 0.58
    image[100:110, 100:110] = 0.0  # no return
    cases = {  # (u, v, z): visible?
        "bump top": ((400, 200, 0.58), True),
        "plane": ((300, 300, 0.6), True),
        "within tol": ((300, 300, 0.602), True),
        "hidden under the bump": ((400, 200, 0.6), False),
        "behind the plane": ((300, 300, 0.62), False),
        "in front of the surface": ((300, 300, 0.55), False),
        "near the border": ((40, 300, 0.6), False),
        "no return": ((105, 105, 0.6), False),
    }
    points = np.array([_point(*uvz) for uvz, _ in cases.values()])
    pixels, depths, _ = project_grasps(points, np.tile([0.0, 0.0, 1.0], (len(points), 1)), K)
    mask = visible_mask(pixels, depths, image)
    assert dict(zip(cases, mask.tolist(), strict=True)) == {name: ok for name, (_, ok) in cases.items()}
    # margin: the rotated 96 px crop must fit for any angle
    edge = THUMBNAIL_GQCNN.crop_radius - 0.5
    inside = visible_mask(np.array([[edge + 0.01, 240.0], [edge - 0.01, 240.0]]), np.array([0.6, 0.6]), _plane())
    assert inside.tolist() == [True, False]
    assert not visible_mask(np.array([[np.nan, 240.0]]), np.array([0.6]), _plane())[0]


def test_pose_vector_depth_and_angle_to_table_normal():
    approaches = np.array([[0.0, 0.0, -2.0], [1.0, 0.0, 0.0], [1.0, 0.0, -1.0], [0.0, 0.0, 1.0]])
    pose = pose_vector(np.array([0.5, 0.6, 0.7, 0.8]), approaches)
    assert pose.dtype == np.float32 and pose.shape == (4, 2)
    np.testing.assert_allclose(pose[:, 0], [0.5, 0.6, 0.7, 0.8])
    np.testing.assert_allclose(pose[:, 1], [0.0, math.pi / 2, math.pi / 4, math.pi], atol=1e-6)


def test_uint8_grid_frames_by_label(tmp_path):
    rng = np.random.default_rng(6)
    thumbs = (PLANE + 0.01 * rng.standard_normal((16, 32, 32))).astype(np.float32)
    labels = np.arange(16) % 2 == 0
    grid = to_uint8_grid(thumbs, labels)
    tile, gap = 32 * 4 + 6, 3
    assert grid.dtype == np.uint8 and grid.shape == (4 * (tile + gap) + gap, 4 * (tile + gap) + gap, 3)
    first, second = grid[gap, gap], grid[gap, 2 * gap + tile]  # top-left corners of the frames
    assert first[1] > 150 > first[0] and second[0] > 150 > second[1]
    save_png(tmp_path / "grid.png", grid)
    assert (tmp_path / "grid.png").stat().st_size > 0


def test_a_dataset_rendered_with_the_sensor_noise_gets_the_cameras_own_error():
    # A flat table 0.6 m away. The simulated sensor's noise is independent per pixel with std
    # base + quadratic (z - offset)^2 = 1.2 mm + 1.9 mm/m^2 x (0.2 m)^2 = 1.276 mm and no bias.
    # The paper's model adds one scale factor per image, alpha ~ Gamma(1000, 1/1000) (std 3.16 %,
    # i.e. 19 mm at 0.6 m, shared by every pixel), and a field of ~4.1 mm pixel std correlated over
    # ~3 px: bumps of millimetres the size of the cup's lip, where the sensor's independent errors
    # average out over the cup's ~130 pixels (its pixel differences: sqrt(2) x 1.276 mm).
    from suctionbench.errors import InputError
    from suctionbench.sensing.noise import NOISE_MODELS, noisy_image

    assert NOISE_MODELS == ("paper", "sensor", "none")
    depth = np.full((240, 320), 0.6, dtype=np.float32)
    sensor = noisy_image(depth, np.random.default_rng(0), "sensor") - depth
    assert abs(float(sensor.mean())) < 2e-5 and float(sensor.std()) == pytest.approx(1.276e-3, rel=0.02)
    assert float(np.diff(sensor, axis=1).std()) == pytest.approx(math.sqrt(2) * 1.276e-3, rel=0.02)
    offsets = [float((noisy_image(depth, np.random.default_rng(s), "paper") - depth).mean()) for s in range(40)]
    assert 0.01 < float(np.std(offsets)) < 0.03  # the image-wide scale error, 19 mm expected
    with pytest.raises(InputError, match="--noise 'kinect': unknown"):
        noisy_image(depth, np.random.default_rng(0), "kinect")


def test_no_noise_returns_the_depth_after_the_sensors_draws():
    # "none", the ideal sensor: the rendered depth to the bit (zeros stay zero), and the generator
    # left where "sensor" leaves it, so everything drawn after the image (the next image's noise,
    # the grasps) is the sensor-noise dataset's: the two datasets are twins but for the noise.
    from suctionbench.sensing.noise import noisy_image

    depth = np.full((60, 80), 0.6, dtype=np.float32)
    depth[:, :10] = 0.0
    ideal_rng, sensor_rng = np.random.default_rng(5), np.random.default_rng(5)
    ideal = noisy_image(depth, ideal_rng, "none")
    sensor = noisy_image(depth, sensor_rng, "sensor")
    np.testing.assert_array_equal(ideal, depth)
    assert ideal.dtype == np.float32 and float(np.abs(sensor - depth).max()) > 1e-3
    assert ideal_rng.random() == sensor_rng.random()


def test_block_mean_thumbnails_average_independent_pixel_noise_and_keep_a_slope():
    # Grasp thumbnails that hold their 3 x 3 block's mean ("mean" sampling) instead of its centre
    # pixel: for independent per-pixel noise of standard deviation s (the simulated sensor's), the
    # mean of 9 pixels has s / 3; point samples keep s. On a plane the mean of a linear function over
    # a block symmetric about the sample point is its value there, so a noise-free slope reads the same.
    mean = ThumbnailConfig(sampling="mean")
    assert mean.block == 3 and THUMBNAIL_CONTEXT.block == 9 and THUMBNAIL_CONTEXT.sampling == "mean"
    rng = np.random.default_rng(11)
    sigma = 0.0013
    noisy = (PLANE + sigma * rng.standard_normal((K.height, K.width))).astype(np.float32)
    pixels = rng.uniform(100, [540, 380], (40, 2)).round() + 0.5  # crops inside; samples on pixel centres
    angles = rng.choice([0.0, math.pi / 2, math.pi, -math.pi / 2], 40)  # axis-aligned
    point = sample_thumbnails(noisy, pixels, angles, THUMBNAIL_GQCNN)
    block = sample_thumbnails(noisy, pixels, angles, mean)
    np.testing.assert_array_equal(point, extract_thumbnails(noisy, pixels, angles))  # gqcnn's as before
    assert np.std(point) == pytest.approx(sigma, rel=0.05)
    assert np.std(block) == pytest.approx(sigma / 3, rel=0.08)
    cols = np.arange(K.width, dtype=np.float32)
    slope = np.broadcast_to(PLANE + 0.0002 * cols, (K.height, K.width))  # 0.2 mm per pixel across the image
    np.testing.assert_allclose(sample_thumbnails(slope, pixels, angles, mean),
                               sample_thumbnails(slope, pixels, angles, THUMBNAIL_GQCNN), atol=1e-6)


def test_thumbnail_configs_refuse_an_unknown_sampling_and_read_back_from_a_card():
    with pytest.raises(InputError, match="sampling = 'median' must be one of point, mean"):
        ThumbnailConfig(sampling="median")
    assert ThumbnailConfig.from_dict({"crop_size": 96, "out_size": 32, "sampling": "mean"}, "card").block == 3
    with pytest.raises(InputError, match="card: thumbnail .* is not a thumbnail config"):
        ThumbnailConfig.from_dict({"crop": 96}, "card")
    with pytest.raises(InputError, match="card: thumbnail config: crop_size = 0"):  # a bad value names the card
        ThumbnailConfig.from_dict({"crop_size": 0}, "card")
    # block means need an odd whole block: an even one's mean centres half a pixel off the sample
    # point (uniform_filter of size 2 averages pixels i - 1 and i), moving the grasp off centre
    for crop in (64, 80):
        with pytest.raises(InputError, match="odd whole number"):
            ThumbnailConfig(crop_size=crop, sampling="mean")
    assert ThumbnailConfig(crop_size=32, sampling="mean").block == 1
    assert ThumbnailConfig(crop_size=64).block == 2  # point samples at any pitch
