"""What each pixel's camera rays meet first: which surface, its normal, its distance (the surfaces' labels and the
auxiliary buffers' model images are made of them)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mcrt.scene import Scene


@dataclass(frozen=True)
class FirstHits:
    """What each pixel's sub x sub pinhole rays meet first (:func:`first_hits`)."""

    counts: np.ndarray  # (H, W, labels) rays meeting each surface of label_names ('nothing' last)
    normal: np.ndarray  # (H, W, 3) mean unit normal at the hits (facing the ray), 0 for rays that meet nothing
    distance: np.ndarray  # (H, W) mean distance from the eye to the hits (rays that meet nothing left out)
    cosines: np.ndarray  # (H, W, labels) sum of |n . d| over the rays meeting each surface (0 for 'nothing')
    ray_distance: np.ndarray  # (H, W, sub * sub) each ray's distance to its hit (inf for nothing)
    ray_depth: np.ndarray  # (H, W, sub * sub) the same along the view axis (a far clip plane's measure)


def nearest(scene: Scene, o: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The first surface each ray o + t d (o one point, shape (3,), or one per ray, (N, 3)) meets: (its label, an
    index of :func:`mcrt.grade.expected.label_names`, the last for nothing; its distance t, inf for nothing; its unit
    normal, facing the ray, 0 for nothing)."""
    surfaces, spheres = scene.surfaces(), scene.spheres()
    nothing = len(surfaces) + len(spheres)
    tris = np.concatenate([s.triangles for s in surfaces])
    owner = np.concatenate([[k] * len(s.triangles) for k, s in enumerate(surfaces)])
    e1, e2 = tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]
    tri_n = np.cross(e1, e2)
    tri_n /= np.linalg.norm(tri_n, axis=1, keepdims=True)
    o = np.asarray(o, float)

    def dot(a, b):  # rows of a with b, one vector or one row each (one eye's rays: the matrix product, as ever)
        return a @ b if b.ndim == 1 else np.sum(a * b, axis=1)

    best_t, best, n = np.full(len(d), np.inf), np.full(len(d), nothing), np.zeros((len(d), 3))
    for t_i in range(len(tris)):  # Moller-Trumbore, one triangle against all rays
        p = np.cross(d, e2[t_i])
        det = p @ e1[t_i]
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            tv = o - tris[t_i, 0]
            uu = dot(p, tv) * inv
            q = np.cross(tv, e1[t_i])
            vv = dot(d, q) * inv
            t = (q @ e2[t_i]) * inv
        ok = (np.abs(det) > 1e-12) & (uu >= 0) & (vv >= 0) & (uu + vv <= 1) & (t > 1e-6) & (t < best_t)
        best_t = np.where(ok, t, best_t)
        best = np.where(ok, owner[t_i], best)
        n = np.where(ok[:, None], tri_n[t_i], n)
    for k, sp in enumerate(spheres):
        oc = o - np.asarray(sp.center)
        b = dot(d, oc)
        disc = b * b - (dot(oc, oc) - sp.radius**2)
        with np.errstate(invalid="ignore"):
            t = -b - np.sqrt(disc)
        ok = (disc > 0) & (t > 1e-6) & (t < best_t)
        best_t = np.where(ok, t, best_t)
        best = np.where(ok, len(surfaces) + k, best)
        n = np.where(ok[:, None], (o + t[:, None] * d - np.asarray(sp.center)) / sp.radius, n)
    n *= np.where(np.sum(n * d, axis=1, keepdims=True) > 0, -1.0, 1.0)  # facing the ray
    return best, best_t, n


def first_hits(scene: Scene, camera: str, width: int, height: int, sub: int = 4) -> FirstHits:
    """Each pixel's sub x sub pinhole rays (stratified at the strata's centres) traced to the first surface they
    meet: which surface, its normal and its distance."""
    from mcrt.camera import primary_directions

    cam = scene.camera(camera)
    jj, ii = np.mgrid[0:height, 0:width]
    n_labels = len(scene.surfaces()) + len(scene.spheres()) + 1
    counts = np.zeros((height, width, n_labels), np.int32)
    normals, dist, hits = np.zeros((height * width, 3)), np.zeros(height * width), np.zeros(height * width)
    cosines = np.zeros((height, width, n_labels))
    ray_t, ray_z = np.zeros((height * width, sub * sub)), np.zeros((height * width, sub * sub))
    forward = cam.frame()[2]
    for su in range(sub):
        for sv in range(sub):
            u = np.full(ii.shape, (su + 0.5) / sub)
            v = np.full(ii.shape, (sv + 0.5) / sub)
            d = primary_directions(cam, width, height, ii, jj, u, v).reshape(-1, 3)
            best, best_t, n = nearest(scene, np.asarray(cam.eye, float), d)
            np.add.at(counts, (jj.ravel(), ii.ravel(), best), 1)
            hit = np.isfinite(best_t)
            np.add.at(cosines, (jj.ravel(), ii.ravel(), best), np.where(hit, np.abs(np.sum(n * d, axis=1)), 0.0))
            normals += np.where(hit[:, None], n, 0.0)
            dist += np.where(hit, best_t, 0.0)
            hits += hit
            ray_t[:, su * sub + sv], ray_z[:, su * sub + sv] = best_t, best_t * (d @ forward)
    return FirstHits(counts, (normals / (sub * sub)).reshape(height, width, 3),
                     (dist / np.maximum(hits, 1)).reshape(height, width), cosines,
                     ray_t.reshape(height, width, -1), ray_z.reshape(height, width, -1))
