"""Household-like shape generators (the "typical" set's objects are specs of them: `objects.typical`).

Every generator builds a single watertight body by constructive solid geometry (manifold3d, through
`union` / `difference`) on lathed profiles, rounded boxes (superellipsoids) and primitives, plus
smooth vertex maps (squared cross-sections, linear tapers). Parameters are plain numbers and lists
in metres and radians, and nothing is random, so (generator, params) fully describes an object.
Objects stand on z = 0 unless said otherwise; x is their long or "front" axis. Generator names
carry the "household_" prefix, which the training corpus samples (objects.corpus), and every
parameter has a working default.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import trimesh

from suctionbench.objects.mass import part
from suctionbench.objects.shapes import (
    box,
    cylinder,
    difference,
    generator,
    placed,
    prism,
    superellipsoid,
    tube,
    union,
)

# -- shared building blocks ----------------------------------------------------------------------


def _lathe(profile: Sequence[tuple[float, float]], sections: int) -> trimesh.Trimesh:
    """Solid of revolution about z of a (radius, z) polyline that starts and ends on the axis."""
    return trimesh.creation.revolve(np.asarray(profile, dtype=float), sections=sections)


def _smoothstep(t: np.ndarray) -> np.ndarray:
    """C1 ramp from 0 (t <= 0) to 1 (t >= 1)."""
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _deformed(mesh: trimesh.Trimesh, vertices: np.ndarray) -> trimesh.Trimesh:
    """`mesh` with its vertices moved (the map must keep orientation, so faces stay outward)."""
    return trimesh.Trimesh(vertices, mesh.faces, process=True)


def _squared_section(
    mesh: trimesh.Trimesh, power: float, depth_ratio: float, z_full: float, z_round: float
) -> trimesh.Trimesh:
    """Deform round horizontal sections into superellipses |x|^p + |y|^p = r^p squashed in y.

    The full deformation (power `power`, y scaled by `depth_ratio`) applies below `z_full` and
    fades smoothly to none (round, p = 2) at `z_round`, so a squared body can carry a round neck.
    """
    v = np.array(mesh.vertices)
    w = _smoothstep((z_round - v[:, 2]) / max(z_round - z_full, 1e-9))
    p = 2.0 + (power - 2.0) * w
    theta = np.arctan2(v[:, 1], v[:, 0])
    scale = (np.abs(np.cos(theta)) ** p + np.abs(np.sin(theta)) ** p) ** (-1.0 / p)
    v[:, :2] *= scale[:, None]
    v[:, 1] *= 1.0 + (depth_ratio - 1.0) * w
    return _deformed(mesh, v)


def _tapered(mesh: trimesh.Trimesh, axis: int, end_scale: Sequence[float]) -> trimesh.Trimesh:
    """Scale the two coordinates across `axis` (about the bounding-box centre line) linearly from
    1 at the low end of `axis` to `end_scale` (one factor per cross axis, in x, y, z order) at the
    high end: wedges, sloped cabins, narrowing jug tops."""
    v = np.array(mesh.vertices)
    lo, hi = mesh.bounds
    centre = (lo + hi) / 2.0
    t = (v[:, axis] - lo[axis]) / (hi[axis] - lo[axis])
    for k, s in zip([a for a in range(3) if a != axis], end_scale, strict=True):
        v[:, k] = centre[k] + (v[:, k] - centre[k]) * (1.0 + (s - 1.0) * t)
    return _deformed(mesh, v)


def _rounded_box(extents: Sequence[float], exponent: float = 0.25, count: int = 24) -> trimesh.Trimesh:
    """Rounded box (superellipsoid) centred at the origin."""
    return superellipsoid(list(extents), exponent=exponent, count=count)


def _rod(radius: float, start: Sequence[float], end: Sequence[float], sections: int) -> trimesh.Trimesh:
    """Solid cylinder of `radius` from point `start` to point `end`."""
    return trimesh.creation.cylinder(radius=radius, segment=[start, end], sections=sections)


def _handle_loop(radius: float, thickness: float, width: float, sections: int = 32) -> trimesh.Trimesh:
    """Closed handle ring in the x-z plane centred at the origin: a torus of centre-line `radius`
    with an elliptical grip section, `thickness` across the ring and `width` along y. Embed part of
    it in a body and cut the inner part away to get a C-shaped handle."""
    ring = trimesh.creation.torus(radius, thickness / 2.0, major_sections=sections, minor_sections=12)
    ring = placed(ring, rotation=(math.pi / 2.0, 0.0, 0.0))
    ring.apply_scale([1.0, width / thickness, 1.0])
    return ring


def _cavity(body: trimesh.Trimesh, wall: float, floor: float) -> trimesh.Trimesh:
    """Cutter that hollows `body` into an open-top container: the body shrunk in x and y by
    `wall` on each side and lifted by `floor`, so it leaves the floor and breaks through the top."""
    lo, hi = body.bounds
    centre = (lo + hi) / 2.0
    size = (hi - lo)[:2]
    v = np.array(body.vertices)
    v[:, :2] = centre[:2] + (v[:, :2] - centre[:2]) * (size - 2.0 * wall) / size
    v[:, 2] += floor
    return _deformed(body, v)


def _open_container(
    body: trimesh.Trimesh, wall: float, floor: float, *attachments: trimesh.Trimesh
) -> trimesh.Trimesh:
    """Hollowed shell of `body` (walls `wall`, floor `floor`, open top) with `attachments` (handles)
    fused on; anything of them that reaches into the cavity is cut away with it."""
    solid = union(body, *attachments) if attachments else body
    return difference(solid, _cavity(body, wall, floor))


def _bottle_body(
    radius: float,
    body_height: float,
    shoulder_height: float,
    neck_radius: float,
    neck_height: float,
    waist: float,
    squareness: float,
    depth_ratio: float,
    sections: int,
    rings: int = 12,
) -> trimesh.Trimesh:
    """Lathed bottle without cap: chamfered foot, body (pinched by `waist` at mid height), smooth
    cosine shoulder and a straight neck; the body section is squared / flattened below the
    shoulder (see `_squared_section`)."""
    chamfer = min(0.004, 0.1 * radius)
    t = np.linspace(0.0, 1.0, rings)
    body_z = chamfer + t * (body_height - chamfer)
    body_r = radius * (1.0 - waist * np.sin(math.pi * t) ** 2)
    s = np.linspace(0.0, 1.0, rings)[1:]
    shoulder_z = body_height + s * shoulder_height
    shoulder_r = neck_radius + (radius - neck_radius) * (1.0 + np.cos(math.pi * s)) / 2.0
    top = body_height + shoulder_height + neck_height
    profile = [(0.0, 0.0), (radius - chamfer, 0.0)]
    profile += list(zip(body_r, body_z, strict=True)) + list(zip(shoulder_r, shoulder_z, strict=True))
    profile += [(neck_radius, top), (0.0, top)]
    mesh = _lathe(profile, sections)
    if squareness != 2.0 or depth_ratio != 1.0:
        mesh = _squared_section(mesh, squareness, depth_ratio, body_height, body_height + shoulder_height)
    return mesh


# -- generators ----------------------------------------------------------------------------------


@generator("household_mug")
def mug(
    radius: float = 0.04,
    height: float = 0.095,
    bottom_radius: float = 0.04,
    wall: float = 0.004,
    floor: float = 0.007,
    handle_radius: float = 0.026,
    handle_thickness: float = 0.009,
    handle_width: float = 0.014,
    handle_offset: float = 0.008,
    sections: int = 40,
) -> trimesh.Trimesh:
    """Mug or cup: lathed body (`radius` at the rim, `bottom_radius` at the foot) hollowed from the
    top with a closed bottom, and a C-shaped handle on +x whose inner half is embedded in the wall
    and cut by the cavity."""
    chamfer = 0.002
    profile = [(0.0, 0.0), (bottom_radius - chamfer, 0.0), (bottom_radius, chamfer), (radius, height), (0.0, height)]
    body = _lathe(profile, sections)
    centre_x = (bottom_radius + radius) / 2.0 + handle_offset
    handle = placed(_handle_loop(handle_radius, handle_thickness, handle_width), (centre_x, 0.0, height / 2.0))
    return _open_container(body, wall, floor, handle)


@generator("household_bottle")
def bottle(
    radius: float = 0.033,
    body_height: float = 0.15,
    shoulder_height: float = 0.04,
    neck_radius: float = 0.013,
    neck_height: float = 0.025,
    cap_radius: float = 0.015,
    cap_height: float = 0.02,
    waist: float = 0.0,
    squareness: float = 2.0,
    depth_ratio: float = 1.0,
    sections: int = 40,
) -> trimesh.Trimesh:
    """Bottle or jar: lathed body, shoulder and neck (round, or squared/flattened like a shampoo
    bottle) and a cylindrical cap whose lower half sits over the top of the neck."""
    body = _bottle_body(
        radius, body_height, shoulder_height, neck_radius, neck_height, waist, squareness, depth_ratio, sections
    )
    top = body_height + shoulder_height + neck_height
    cap = placed(cylinder(cap_radius, cap_height, sections), (0.0, 0.0, top))
    return union(body, cap)


@generator("household_spray_bottle")
def spray_bottle(
    radius: float = 0.045,
    body_height: float = 0.13,
    shoulder_height: float = 0.025,
    neck_radius: float = 0.014,
    neck_height: float = 0.02,
    squareness: float = 4.0,
    depth_ratio: float = 0.6,
    head: Sequence[float] = (0.06, 0.03, 0.04),
    head_offset: float = 0.01,
    nozzle_radius: float = 0.006,
    nozzle_length: float = 0.012,
    trigger: Sequence[float] = (0.012, 0.016, 0.035),
    sections: int = 40,
) -> trimesh.Trimesh:
    """Trigger spray bottle: flattened squared bottle body and neck, a rounded trigger head block
    sitting on the neck and reaching forward (+x), a nozzle, and a trigger hanging under the head."""
    body = _bottle_body(
        radius, body_height, shoulder_height, neck_radius, neck_height, 0.0, squareness, depth_ratio, sections
    )
    neck_top = body_height + shoulder_height + neck_height
    hx, _, hz = head
    head_centre = np.array([head_offset, 0.0, neck_top + hz / 2.0 - 0.008])
    head_block = placed(_rounded_box(head, exponent=0.3), head_centre)
    front = head_centre[0] + hx / 2.0
    nozzle = _rod(nozzle_radius, (front - 0.004, 0.0, head_centre[2]), (front + nozzle_length, 0.0, head_centre[2]), 24)
    tx, _, tz = trigger
    trigger_centre = (front - tx / 2.0 - 0.004, 0.0, head_centre[2] - hz / 2.0 - tz / 2.0 + 0.006)
    trigger_block = placed(_rounded_box(trigger, exponent=0.4), trigger_centre)
    return union(body, head_block, nozzle, trigger_block)


@generator("household_stapler")
def stapler(
    length: float = 0.16,
    width: float = 0.038,
    base_height: float = 0.016,
    arm_height: float = 0.02,
    gap: float = 0.008,
    hinge_length: float = 0.03,
    tilt: float = 0.04,
    exponent: float = 0.3,
) -> trimesh.Trimesh:
    """Desk stapler: long rounded base, a hinge block at the rear (-x) and a top arm pivoting
    about it, lifted at the front by `tilt` (rad)."""
    base = placed(_rounded_box((length, width, base_height), exponent), (0.0, 0.0, base_height / 2.0))
    hinge_top = base_height + gap + arm_height
    hinge = placed(
        _rounded_box((hinge_length, 0.8 * width, hinge_top), exponent),
        (-length / 2.0 + hinge_length / 2.0, 0.0, hinge_top / 2.0),
    )
    arm_length = 0.96 * length
    arm = placed(_rounded_box((arm_length, 0.9 * width, arm_height), exponent), (arm_length / 2.0, 0.0, 0.0))
    arm = placed(arm, (-length / 2.0 + 0.002, 0.0, base_height + gap + arm_height / 2.0), rotation=(0.0, -tilt, 0.0))
    return union(base, hinge, arm)


@generator("household_jug")
def jug(
    width: float = 0.15,
    depth: float = 0.09,
    height: float = 0.2,
    exponent: float = 0.25,
    top_depth_scale: float = 0.8,
    hole: Sequence[float] = (0.045, 0.08),
    grip: float = 0.024,
    cap_radius: float = 0.022,
    cap_height: float = 0.025,
    sections: int = 32,
) -> trimesh.Trimesh:
    """Detergent or milk jug: rounded box body narrowing in depth towards the top, a through-hole
    in the upper rear (+x) corner that leaves a handle loop of thickness `grip`, and a screw cap on
    the top front (-x)."""
    body = placed(_rounded_box((width, depth, height), exponent, count=32), (0.0, 0.0, height / 2.0))
    body = _tapered(body, 2, (1.0, top_depth_scale))
    hole_w, hole_h = hole
    cutter = placed(
        _rounded_box((hole_w, 2.0 * depth, hole_h), exponent=0.5),
        (width / 2.0 - grip - hole_w / 2.0, 0.0, height - grip - hole_h / 2.0),
    )
    cap_x = -width / 2.0 + 2.0 * cap_radius
    cap = _rod(cap_radius, (cap_x, 0.0, height - 0.01), (cap_x, 0.0, height + cap_height), sections)
    return difference(union(body, cap), cutter)


@generator("household_hammer")
def hammer(
    handle_length: float = 0.2,
    handle_width: float = 0.028,
    handle_depth: float = 0.02,
    head_radius: float = 0.013,
    poll_length: float = 0.045,
    claw_length: float = 0.06,
    claw_droop: float = 0.25,
    slot_width: float = 0.005,
    sections: int = 32,
) -> trimesh.Trimesh:
    """Claw hammer: oval handle along z, cylindrical head along x (striking poll on -x), and a
    tapered, drooping claw on +x split by a V-slot."""
    handle = placed(_rounded_box((handle_width, handle_depth, handle_length), 0.35), (0.0, 0.0, handle_length / 2.0))
    return union(handle, *_hammer_head_pieces(handle_length, head_radius, poll_length, claw_length, claw_droop,
                                              slot_width, sections))


@part("household_hammer.head")
def hammer_head(
    handle_length: float = 0.2,
    handle_width: float = 0.028,
    handle_depth: float = 0.02,
    head_radius: float = 0.013,
    poll_length: float = 0.045,
    claw_length: float = 0.06,
    claw_droop: float = 0.25,
    slot_width: float = 0.005,
    sections: int = 32,
) -> trimesh.Trimesh:
    """The hammer's steel head: the cylindrical poll and the claw (the handle's end inside it
    included, as a wedged handle fills the eye)."""
    return union(*_hammer_head_pieces(handle_length, head_radius, poll_length, claw_length, claw_droop, slot_width,
                                      sections))


def _hammer_head_pieces(
    handle_length: float, head_radius: float, poll_length: float, claw_length: float, claw_droop: float,
    slot_width: float, sections: int,
) -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    """The hammer head's poll cylinder and its claw."""
    head_z = handle_length - 0.5 * head_radius
    head = _rod(head_radius, (-poll_length, 0.0, head_z), (0.5 * head_radius, 0.0, head_z), sections)
    claw = box([claw_length, 1.8 * head_radius, 1.5 * head_radius])
    claw = _tapered(claw, 0, (0.8, 0.3))
    slot = _tapered(box([0.7 * claw_length, 0.3 * slot_width, 4.0 * head_radius]), 0, (1.0 / 0.3, 1.0))
    claw = difference(claw, placed(slot, (0.35 * claw_length, 0.0, 0.0)))
    claw = placed(placed(claw, (claw_length / 2.0, 0.0, 0.0)), (0.0, 0.0, head_z), rotation=(0.0, claw_droop, 0.0))
    return head, claw


@generator("household_screwdriver")
def screwdriver(
    handle_length: float = 0.11,
    handle_radius: float = 0.018,
    flats: int = 5,
    flat_depth: float = 0.004,
    shaft_radius: float = 0.003,
    shaft_length: float = 0.1,
    tip_width: float = 0.006,
    tip_thickness: float = 0.0012,
    sections: int = 36,
) -> trimesh.Trimesh:
    """Screwdriver: lathed, gently bulged handle with `flats` planar facets cut along it, a
    narrowing ferrule, a round steel shaft along z and a flat blade tip."""
    grip_top = 0.8 * handle_length
    t = np.linspace(0.0, 1.0, 16)
    grip = [(handle_radius * (0.92 + 0.08 * np.sin(math.pi * u)), 0.004 + u * (grip_top - 0.004)) for u in t]
    ferrule = [
        (handle_radius * (0.4 + 0.52 * (1.0 + math.cos(math.pi * u)) / 2.0), grip_top + u * (handle_length - grip_top))
        for u in t[1:]
    ]
    profile = [(0.0, 0.0), (0.92 * handle_radius - 0.004, 0.0), *grip, *ferrule, (0.0, handle_length)]
    handle = _lathe(profile, sections)
    flat = box([0.02, 0.05, 0.65 * handle_length])
    flat = placed(flat, (handle_radius - flat_depth + 0.01, 0.0, 0.42 * handle_length))
    cutters = [placed(flat, rotation=(0.0, 0.0, a)) for a in 2.0 * math.pi * np.arange(flats) / flats]
    handle = difference(handle, *cutters) if flats else handle
    shaft, blade = _screwdriver_shaft_pieces(handle_length, shaft_radius, shaft_length, tip_width, tip_thickness)
    return union(handle, shaft, blade)


@part("household_screwdriver.shaft")
def screwdriver_shaft(
    handle_length: float = 0.11,
    handle_radius: float = 0.018,
    flats: int = 5,
    flat_depth: float = 0.004,
    shaft_radius: float = 0.003,
    shaft_length: float = 0.1,
    tip_width: float = 0.006,
    tip_thickness: float = 0.0012,
    sections: int = 36,
) -> trimesh.Trimesh:
    """The screwdriver's steel shaft and blade (with the 1 cm of shaft set into the handle)."""
    return union(*_screwdriver_shaft_pieces(handle_length, shaft_radius, shaft_length, tip_width, tip_thickness))


def _screwdriver_shaft_pieces(
    handle_length: float, shaft_radius: float, shaft_length: float, tip_width: float, tip_thickness: float
) -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    """The screwdriver's round shaft and its flat blade."""
    top = handle_length + shaft_length
    shaft = _rod(shaft_radius, (0.0, 0.0, handle_length - 0.01), (0.0, 0.0, top), 24)
    blade = _tapered(box([tip_width, 2.0 * shaft_radius, 0.012]), 2, (1.0, tip_thickness / (2.0 * shaft_radius)))
    blade = placed(blade, (0.0, 0.0, top))
    return shaft, blade


@generator("household_wrench")
def wrench(
    length: float = 0.19,
    bar_width: float = 0.026,
    thickness: float = 0.008,
    ring_radius: float = 0.02,
    hex_size: float = 0.017,
    jaw_radius: float = 0.022,
    jaw_opening: float = 0.017,
    jaw_angle: float = 0.26,
    sections: int = 36,
) -> trimesh.Trimesh:
    """Combination wrench lying flat (thin along z): a slightly thinner rounded bar joining a ring
    end with a hexagonal socket (+x) and an open jaw turned by `jaw_angle` (rad) on -x."""
    bar = _rounded_box((length, bar_width, 0.8 * thickness), exponent=0.1)
    ring = placed(cylinder(ring_radius, thickness, sections), (length / 2.0, 0.0, 0.0))
    jaw = placed(cylinder(jaw_radius, thickness, sections), (-length / 2.0, 0.0, 0.0))
    socket = placed(prism(6, hex_size / math.sqrt(3.0), 2.0 * thickness), (length / 2.0, 0.0, 0.0))
    direction = np.array([-math.cos(jaw_angle), math.sin(jaw_angle), 0.0])
    slot = placed(
        box([2.0 * jaw_radius, jaw_opening, 2.0 * thickness]),
        np.array([-length / 2.0, 0.0, 0.0]) + jaw_radius * direction,
        rotation=(0.0, 0.0, -jaw_angle),
    )
    throat = placed(cylinder(jaw_opening / 2.0, 2.0 * thickness, 24), (-length / 2.0, 0.0, 0.0))
    return difference(union(bar, ring, jaw), socket, slot, throat)


@generator("household_toy_car")
def toy_car(
    length: float = 0.12,
    width: float = 0.055,
    body_height: float = 0.028,
    cabin_length: float = 0.06,
    cabin_height: float = 0.024,
    cabin_offset: float = -0.01,
    windshield_slope: float = 0.7,
    wheel_radius: float = 0.014,
    wheel_width: float = 0.01,
    clearance: float = 0.008,
    sections: int = 32,
) -> trimesh.Trimesh:
    """Toy car or truck: rounded box body, a cabin on top narrowing upwards (sloped windows, set
    back by `cabin_offset` along x) and four wheels half sunk into the body sides."""
    body_z = clearance + body_height / 2.0
    body = placed(_rounded_box((length, width, body_height), 0.3), (0.0, 0.0, body_z))
    cabin = _tapered(_rounded_box((cabin_length, 0.85 * width, cabin_height + 0.006), 0.3), 2, (windshield_slope, 0.9))
    cabin = placed(cabin, (cabin_offset, 0.0, clearance + body_height + cabin_height / 2.0 - 0.003))
    wheel = placed(cylinder(wheel_radius, wheel_width, sections), rotation=(math.pi / 2.0, 0.0, 0.0))
    x = length / 2.0 - 1.5 * wheel_radius
    y = width / 2.0 - wheel_width / 2.0 + 0.002
    wheels = [placed(wheel, (sx * x, sy * y, wheel_radius)) for sx in (-1.0, 1.0) for sy in (-1.0, 1.0)]
    return union(body, cabin, *wheels)


@generator("household_block_stack")
def block_stack(
    blocks: Sequence[Sequence[float]] = ((0.06, 0.06, 0.03), (0.04, 0.04, 0.04)),
    yaws: Sequence[float] = (),
    shifts: Sequence[Sequence[float]] = (),
    exponent: float = 0.0,
    embed: float = 0.001,
) -> trimesh.Trimesh:
    """Toy blocks stacked along z: each block (x, y, z extents) turned by its yaw (rad), shifted by
    its (dx, dy) and sunk `embed` into the one below (missing yaws and shifts are zero); sharp
    boxes, or rounded ones for exponent > 0."""
    yaws = [*yaws, *[0.0] * (len(blocks) - len(yaws))]
    shifts = [*shifts, *[(0.0, 0.0)] * (len(blocks) - len(shifts))]
    parts, z = [], 0.0
    for extents, yaw, (dx, dy) in zip(blocks, yaws, shifts, strict=True):
        block = _rounded_box(extents, exponent) if exponent > 0 else box(list(extents))
        parts.append(placed(block, (dx, dy, z + extents[2] / 2.0), (0.0, 0.0, yaw)))
        z += extents[2] - embed
    return union(*parts)


@generator("household_bowl")
def bowl(
    radius: float = 0.07,
    wall: float = 0.004,
    depth: float = 0.05,
    foot_radius: float = 0.03,
    foot_height: float = 0.007,
    sections: int = 32,
) -> trimesh.Trimesh:
    """Bowl: spherical shell (outer sphere minus a concentric inner one) cut flat at the rim,
    `depth` above the outer bottom, on a foot ring with a recessed underside."""
    sphere = trimesh.creation.uv_sphere(radius, count=[sections, sections])
    inner = trimesh.creation.uv_sphere(radius - wall, count=[sections, sections])
    rim_z = -radius + depth
    above_rim = placed(box([3.0 * radius] * 3), (0.0, 0.0, rim_z + 1.5 * radius))
    foot_top = -math.sqrt(radius**2 - foot_radius**2) + 0.5 * wall
    foot_bottom = -radius - foot_height
    foot = _rod(foot_radius, (0.0, 0.0, foot_bottom), (0.0, 0.0, foot_top), sections)
    recess = _rod(
        foot_radius - 0.004, (0.0, 0.0, foot_bottom - 0.001), (0.0, 0.0, foot_bottom + 0.5 * foot_height), sections
    )
    mesh = difference(union(sphere, foot), inner, above_rim, recess)
    return placed(mesh, (0.0, 0.0, -foot_bottom))


@generator("household_tray")
def tray(
    length: float = 0.12,
    width: float = 0.08,
    height: float = 0.025,
    wall: float = 0.005,
    floor: float = 0.005,
    exponent: float = 0.3,
    ribs: int = 0,
    rib_height: float = 0.003,
) -> trimesh.Trimesh:
    """Open tray (soap dish, pen tray, storage box): hollowed rounded box, optionally with `ribs`
    drainage ribs across the floor."""
    body = placed(_rounded_box((length, width, height), exponent, count=28), (0.0, 0.0, height / 2.0))
    shell = _open_container(body, wall, floor)
    if not ribs:
        return shell
    pitch = (length - 2.0 * wall) / (ribs + 1)
    rib = box([0.003, 0.75 * (width - 2.0 * wall), rib_height + 0.001])
    xs = -length / 2.0 + wall + pitch * np.arange(1, ribs + 1)
    return union(shell, *[placed(rib, (x, 0.0, floor + rib_height / 2.0 - 0.0005)) for x in xs])


@generator("household_tape_roll")
def tape_roll(
    outer_radius: float = 0.055,
    inner_radius: float = 0.038,
    core_thickness: float = 0.003,
    width: float = 0.048,
    core_extra: float = 0.002,
    sections: int = 48,
) -> trimesh.Trimesh:
    """Roll of tape lying flat: a thick tape annulus (`inner_radius` to `outer_radius`) wound on a
    cardboard core of `core_thickness` inside it that stands `core_extra` proud of the tape (the
    core reaches 1 mm into the tape so the two fuse)."""
    tape = tube(outer_radius, inner_radius, width, sections)
    core = tube(inner_radius + 0.001, inner_radius - core_thickness, width + core_extra, sections)
    return placed(union(tape, core), (0.0, 0.0, (width + core_extra) / 2.0))


@generator("household_can")
def can(
    radius: float = 0.033,
    height: float = 0.122,
    top_radius: float = 0.027,
    neck_height: float = 0.012,
    foot_radius: float = 0.025,
    foot_height: float = 0.008,
    dome: float = 0.008,
    lid_depth: float = 0.004,
    rim_width: float = 0.0015,
    beads: int = 0,
    bead_depth: float = 0.0006,
    sections: int = 40,
) -> trimesh.Trimesh:
    """Drink or food can: lathed body with a domed bottom on a standing ring, optional side
    beads, a neck to the top rim (narrower for drink cans, flush or wider for food cans) and a lid
    recessed `lid_depth` inside the rim."""
    rings = max(2, 6 * beads + 2)
    t = np.linspace(0.0, 1.0, rings)
    body_z = foot_height + t * (height - neck_height - foot_height)
    body_r = radius - bead_depth * 0.5 * (1.0 - np.cos(2.0 * math.pi * beads * t))
    s = np.linspace(0.0, 1.0, 8)[1:]
    neck_z = height - neck_height + s * (neck_height - 0.002)
    neck_r = top_radius + (radius - top_radius) * (1.0 + np.cos(math.pi * s)) / 2.0
    profile = [(0.0, dome), (foot_radius, 0.0), (foot_radius + 0.002, 0.0)]
    profile += list(zip(body_r, body_z, strict=True)) + list(zip(neck_r, neck_z, strict=True))
    profile += [(top_radius, height), (top_radius - rim_width, height)]
    profile += [(top_radius - rim_width, height - lid_depth), (0.0, height - lid_depth)]
    return _lathe(profile, sections)
