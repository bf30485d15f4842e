# Run from the repository root: python scenes/meshes/make_l_bracket.py
"""Writes scenes/meshes/l_bracket.stl: an L-bracket (mm), the L profile in the
xz plane extruded 30 mm along y. Foot 40 x 4 mm on z = 0, upright 4 x 50 mm at x = 0."""
import numpy as np, trimesh
profile = np.array([(0, 0), (40, 0), (40, 4), (4, 4), (4, 50), (0, 50)], float)
cap = [(3, 4, 5), (3, 5, 0), (3, 0, 1), (3, 1, 2)]   # fan from the inner corner
n = len(profile)
v = np.array([(x, y, z) for y in (-15, 15) for x, z in profile])
faces = [tuple(i for i in t) for t in cap] + [tuple(i + n for i in t[::-1]) for t in cap]
for i in range(n):
    j = (i + 1) % n
    faces += [(i, j + n, j), (i, i + n, j + n)]
m = trimesh.Trimesh(v, faces, process=True)
assert m.is_watertight and m.is_winding_consistent and m.volume > 0, "bracket must be closed, outward"
print(m.volume, m.bounds)
m.export("scenes/meshes/l_bracket.stl")
