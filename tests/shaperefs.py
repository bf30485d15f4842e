"""Reference data shared by the shape tests: primitive sizes and the
generalised winding number (inside or outside a closed mesh, by brute force).
Not a test file."""

import numpy as np

from cablecheck.checker.shapes import ShapeType

SIZES = {
    ShapeType.BOX: [0.3, 0.2, 0.1],
    ShapeType.SPHERE: [0.25],
    ShapeType.CYLINDER: [0.2, 0.35],
    ShapeType.CAPSULE: [0.15, 0.3],
    ShapeType.ELLIPSOID: [0.4, 0.25, 0.1],
}


def winding_number(m, p):
    """Generalised winding number (van Oosterom and Strackee solid angles)."""
    a = m.vertices[m.faces[:, 0]][None] - p[:, None]
    b = m.vertices[m.faces[:, 1]][None] - p[:, None]
    c = m.vertices[m.faces[:, 2]][None] - p[:, None]
    la, lb, lc = (np.linalg.norm(x, axis=2) for x in (a, b, c))
    num = np.einsum("nfj,nfj->nf", a, np.cross(b, c))
    den = la * lb * lc + np.einsum("nfj,nfj->nf", a, b) * lc + np.einsum("nfj,nfj->nf", b, c) * la
    den += np.einsum("nfj,nfj->nf", c, a) * lb
    return np.sum(2 * np.arctan2(num, den), axis=1) / (4 * np.pi)
