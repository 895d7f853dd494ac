#!/usr/bin/env python3
"""Checks a `stand` run on its own, sharing no code with Spec2Fab.

From the print's slice stack (print/slices: one indexed PNG per layer) and
the material library's densities it computes the print's centre of mass;
from the experiment's mesh (an STL) it computes the support polygon (the
convex hull of the vertices within the contact tolerance of the lowest,
along gravity) and the solid shape's centroid. It then checks that

  - the centre of mass agrees with result.json's stand.tuned.centre_mm
    within --tolerance-mm (0.1 mm);
  - its projection lies inside the support polygon with the goal's margin;
  - the shape printed solid (uniform density: the mesh's centroid) does not.

Printers whose cavities fill with support (a "support_material" in the
profile: PolyJet) are refused: this check weighs void voxels as empty.

  tools/check_stand.py EXPERIMENT.json RUN_FOLDER [--tolerance-mm 0.1]

Prints what it measured, one line each, and exits 0 when every check holds,
1 when one fails, 2 on unusable input. Needs numpy and Pillow.
"""

import argparse
import json
import pathlib
import struct
import sys

import numpy as np
from PIL import Image


def read_stl(path):
    """Triangles (n, 3, 3) of a binary or ASCII STL."""
    data = path.read_bytes()
    if len(data) >= 84:
        count = struct.unpack_from("<I", data, 80)[0]
        if 84 + 50 * count == len(data):
            records = np.frombuffer(data, dtype=np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")]),
                                    count=count, offset=84)
            return records["v"].astype(np.float64)
    vertices = [list(map(float, line.split()[1:4])) for line in data.decode("ascii").splitlines()
                if line.strip().startswith("vertex")]
    return np.array(vertices, dtype=np.float64).reshape(-1, 3, 3)


def mesh_centroid(triangles):
    """Centroid of the solid a closed mesh bounds (signed tetrahedra from the origin)."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    volumes = np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0
    return (volumes[:, None] * (a + b + c) / 4.0).sum(axis=0) / volumes.sum()


def floor_basis(down):
    up = -down
    helper = np.array([1.0, 0, 0]) if abs(up[0]) < 0.9 else np.array([0, 1.0, 0])
    u = helper - helper.dot(up) * up
    u /= np.linalg.norm(u)
    return u, np.cross(up, u)


def convex_hull(points):
    """Andrew's monotone chain: the hull counter-clockwise."""
    pts = sorted(set(map(tuple, np.round(points, 9))))
    if len(pts) <= 2:
        return np.array(pts)

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1])


def margin(hull, p):
    """Signed distance from p to the hull's boundary, positive inside."""
    nearest, inside = np.inf, len(hull) >= 3
    for i in range(len(hull)):
        a, b = hull[i], hull[(i + 1) % len(hull)]
        ab = b - a
        t = np.clip((p - a).dot(ab) / max(ab.dot(ab), 1e-300), 0.0, 1.0)
        nearest = min(nearest, np.linalg.norm(a + t * ab - p))
        if ab[0] * (p - a)[1] - ab[1] * (p - a)[0] < 0:
            inside = False
    return nearest if inside else -nearest


def slice_centre_of_mass(slices, library):
    manifest = json.loads((slices / "manifest.json").read_text())
    density = {m["name"]: m["mechanical"]["density_kg_m3"]["value"] for m in library["materials"]
               if "density_kg_m3" in m.get("mechanical", {})}
    by_index = np.full(256, np.nan)  # NaN: a material without a density, or no material
    names = {}
    for entry in manifest["palette"]:
        names[entry["index"]] = entry["material"]
        by_index[entry["index"]] = 0.0 if entry["material"] == "void" else density.get(entry["material"], np.nan)
    vx, vy, vz = manifest["voxel_mm"]
    x0, y0, z0 = manifest["first_voxel_centre_mm"]
    width, height = manifest["width"], manifest["height"]
    xs = x0 + vx * np.arange(width)
    ys = y0 + vy * (height - 1 - np.arange(height))  # row 0 = largest y
    mass = 0.0
    moment = np.zeros(3)
    for layer in range(manifest["layers"]):
        image = Image.open(slices / f"slice_{layer:05d}.png")
        if image.mode not in ("P", "L"):
            raise ValueError(f"{slices}/slice_{layer:05d}.png: not an indexed image ({image.mode})")
        indices = np.asarray(image)
        rho = by_index[indices]
        if np.isnan(rho).any():
            index = int(indices[np.isnan(rho)][0])
            raise ValueError(f"slice {layer}: {names.get(index, f'palette index {index}')} has no density in the library")
        column = rho.sum(axis=0)  # per x
        row = rho.sum(axis=1)     # per y
        total = column.sum()
        mass += total
        moment += (column.dot(xs), row.dot(ys), total * (z0 + vz * layer))
    voxel_volume_m3 = vx * vy * vz * 1e-9
    return mass * voxel_volume_m3, moment / mass


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("experiment", type=pathlib.Path)
    parser.add_argument("run", type=pathlib.Path)
    parser.add_argument("--tolerance-mm", type=float, default=0.1)
    args = parser.parse_args()
    try:
        experiment = json.loads(args.experiment.read_text())
        result = json.loads((args.run / "result.json").read_text())
        base = args.experiment.parent
        mesh = read_stl(base / experiment["geometry"]["mesh"])
        library = json.loads((base / experiment["materials"]).read_text())
        printer = json.loads((base / experiment["printer"]).read_text())
        goal = experiment.get("goal", {})
        stand = result["stand"]
        reported = np.array(stand["tuned"]["centre_mm"], dtype=np.float64)
        reported_mass = float(stand["tuned"]["mass_kg"])
        down = np.array(goal.get("gravity", [0, 0, -1]), dtype=np.float64)
    except (OSError, KeyError, TypeError, ValueError) as error:
        print(f"check_stand: unusable input: {error}", file=sys.stderr)
        return 2
    if printer.get("support_material"):
        # Its cavities fill with support (PolyJet): a void voxel inside the
        # shell is not empty, and this check weighs void as nothing.
        print(f"check_stand: printer {printer.get('name', '?')} fills cavities with {printer['support_material']}; "
              "this check weighs void voxels as empty and covers printers without a support material (FDM)",
              file=sys.stderr)
        return 2
    if not np.all(np.isfinite(down)) or not np.any(down):
        print("check_stand: goal.gravity must be a finite direction, not [0, 0, 0]", file=sys.stderr)
        return 2
    down /= np.linalg.norm(down)
    tolerance = goal.get("contact_tolerance_mm", 0.5)
    margin_goal = goal.get("margin_mm", 1.0)
    u, v = floor_basis(down)
    vertices = mesh.reshape(-1, 3)
    heights = vertices.dot(down)
    contact = vertices[heights >= heights.max() - tolerance]
    hull = convex_hull(np.stack([contact.dot(u), contact.dot(v)], axis=1))

    def projected(p):
        return np.array([p.dot(u), p.dot(v)])

    try:
        mass, centre = slice_centre_of_mass(args.run / "print" / "slices", library)
    except (OSError, KeyError, ValueError) as error:
        print(f"check_stand: unusable slices: {error}", file=sys.stderr)
        return 2
    solid_centre = mesh_centroid(mesh)
    tuned_margin, solid_margin = margin(hull, projected(centre)), margin(hull, projected(solid_centre))
    distance = np.linalg.norm(centre - reported)
    print(f"support polygon: {len(hull)} corners, from {len(contact)} vertices within {tolerance} mm of the lowest")
    print(f"centre of mass from the slices: [{centre[0]:.3f}, {centre[1]:.3f}, {centre[2]:.3f}] mm, "
          f"mass {mass * 1e3:.2f} g (report: {reported_mass * 1e3:.2f} g)")
    print(f"reported centre of mass: [{reported[0]:.3f}, {reported[1]:.3f}, {reported[2]:.3f}] mm: "
          f"{distance:.3f} mm apart (at most {args.tolerance_mm})")
    print(f"tuned: {tuned_margin:+.3f} mm from the support's edge (at least {margin_goal} asked)")
    print(f"solid (the mesh's centroid): {solid_margin:+.3f} mm from the support's edge")
    checks = [("centres agree", distance <= args.tolerance_mm),
              ("tuned stands with the margin", tuned_margin >= margin_goal),
              ("solid falls", solid_margin < 0)]
    for name, held in checks:
        print(f"{'ok' if held else 'FAILED'}: {name}")
    return 0 if all(held for _, held in checks) else 1


if __name__ == "__main__":
    sys.exit(main())
