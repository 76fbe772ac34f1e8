"""The scene file: loading, validation errors, geometry invariants, hashing."""

from __future__ import annotations

import copy
import tomllib

import numpy as np
import pytest

from mcrt.scene import CANONICAL, SceneError, load_scene, scene_from_dict


@pytest.fixture(scope="module")
def raw():
    return tomllib.loads(CANONICAL.read_text())


@pytest.fixture(scope="module")
def scene():
    return load_scene()


def test_canonical_numbers_match_the_design(scene):
    """Spot checks against scene.md, so that the file cannot drift silently."""
    assert scene.room.floor_z == -5 and scene.room.ceiling_z == 5
    assert scene.room.corners["D"] == (13.0, 0.0)
    assert scene.light.center == (5.0, 0.0, 4.99) and scene.light.size == (2.0, 2.0)
    assert scene.light.radiance == (20.0, 20.0, 20.0) and scene.light.normal == (0.0, 0.0, -1.0)
    sphere = scene.spheres()[0]
    assert sphere.center == (9.5, 2.0, -3.3) and sphere.radius == 1.5
    assert scene.cameras["far"].fov_x_deg == pytest.approx(2 * np.degrees(np.arctan(0.5)), abs=1e-12)
    assert scene.presets["course2023"] == {"width": 800, "height": 800, "spp": 100, "light_samples": 30, "max_depth": 8}


def test_round_trip_through_the_canonical_dict(scene, raw):
    """Loading, re-serialising what the hash covers, and loading again changes nothing."""
    again = scene_from_dict(copy.deepcopy(raw), "again.toml")
    assert again.canonical_dict() == scene.canonical_dict()
    assert again.content_hash() == scene.content_hash()


def test_hash_ignores_formatting_but_not_content(raw, tmp_path):
    text = CANONICAL.read_text()
    reformatted = "# a comment\n" + text.replace(" = ", "=")
    p = tmp_path / "reformatted.toml"
    p.write_text(reformatted)
    base = load_scene().content_hash()
    assert load_scene(p).content_hash() == base
    d = copy.deepcopy(raw)
    d["room"]["walls"][0]["albedo"][0] = 0.7501
    assert scene_from_dict(d).content_hash() != base
    d = copy.deepcopy(raw)
    d["render"]["spp"] = 999  # render defaults are not part of the scene's identity
    assert scene_from_dict(d).content_hash() == base


def test_room_is_closed_and_faces_point_inwards(scene):
    """Every room triangle's normal points into the room; the faces tile the boundary."""
    centroid = np.array([5.0, 0.0, 0.0])
    total_area = 0.0
    for surf in scene.surfaces():
        for tri in surf.triangles:
            n = np.cross(tri[1] - tri[0], tri[2] - tri[0])
            area = 0.5 * np.linalg.norm(n)
            assert area > 0, surf.name
            c = tri.mean(axis=0)
            if surf.name.startswith(("wall", "floor", "ceiling")):
                assert n @ (centroid - c) > 0, f"{surf.name} faces outwards"
                total_area += area
            elif surf.name == "tetrahedron":
                inner = np.mean(np.array(scene.objects[0].vertices), axis=0)
                assert n @ (c - inner) > 0, "tetrahedron face points inwards"
            elif surf.name == "light":
                assert n[2] < 0, "the light's triangles must face down"
    # Closed prism: the area of its faces equals 2 * floor area + perimeter * height.
    poly = scene.room.polygon()
    x, y = poly[:, 0], poly[:, 1]
    floor_area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    perimeter = np.sum(np.linalg.norm(poly - np.roll(poly, -1, axis=0), axis=1))
    assert total_area == pytest.approx(2 * floor_area + perimeter * 10.0, rel=1e-12)
    # Every edge of the room's triangles is shared by exactly two triangles (watertight).
    edges: dict = {}
    for surf in scene.surfaces():
        if surf.name.startswith(("wall", "floor", "ceiling")):
            for tri in surf.triangles:
                for a, b in ((0, 1), (1, 2), (2, 0)):
                    key = tuple(sorted((tuple(tri[a]), tuple(tri[b]))))
                    edges[key] = edges.get(key, 0) + 1
    # Fan triangulation and wall quads meet at corners only, so edges are shared or lie on a
    # longer collinear edge; check the closedness through the directed-edge balance instead.
    directed: dict = {}
    for surf in scene.surfaces():
        if surf.name.startswith(("wall", "floor", "ceiling")):
            for tri in surf.triangles:
                for a, b in ((0, 1), (1, 2), (2, 0)):
                    directed[(tuple(tri[a]), tuple(tri[b]))] = directed.get((tuple(tri[a]), tuple(tri[b])), 0) + 1
    for (a, b), k in directed.items():
        assert directed.get((b, a), 0) == k, f"edge {a}->{b} has no opposite: the room is not closed"


def test_planes_contain_the_room(scene):
    assert scene.room.contains((5, 0, 0))
    assert not scene.room.contains((14, 0, 0))
    assert not scene.room.contains((5, 0, 5.5))
    for p in scene.room.polygon():
        assert scene.room.contains((*p, 0.0), margin=-1e-9)


def test_settings_preset_and_overrides(scene):
    s = scene.settings("course2023", spp=7)
    assert (s.width, s.spp, s.light_samples, s.max_depth) == (800, 7, 30, 8)
    with pytest.raises(SceneError, match="presets: no preset named 'nope'"):
        scene.settings("nope")
    with pytest.raises(SceneError, match="render.spp"):
        scene.settings(spp=0)


# ---- every validation error, from a bad file --------------------------------------------


def _edit(raw, fn):
    d = copy.deepcopy(raw)
    fn(d)
    return d


BAD = {
    "missing field": (lambda d: d["room"].pop("floor_z"), r"room\.floor_z: missing required field"),
    "misspelt field": (lambda d: d["room"]["walls"][0].update(albdo=d["room"]["walls"][0].pop("albedo")), r"room\.walls\[0\]\.albdo: unknown field \(did you mean 'albedo'\?\)"),
    "misspelt top-level": (lambda d: d.update(lihgt=d.pop("light")), r"lihgt: unknown field \(did you mean 'light'\?\)"),
    "degenerate triangle": (lambda d: d["objects"][0].update(vertices=[[7.5, -2, -4.9], [8.5, -2, -4.9], [9.5, -2, -4.9], [8.5, -2.3, -2]]), r"objects\[0\]\.vertices: degenerate triangle"),
    "light facing away": (lambda d: d["light"].update(normal=[0.0, 0.0, 1.0]), r"light\.normal: the light faces away from the room"),
    "light tilted": (lambda d: d["light"].update(normal=[0.0, 1.0, 0.0]), r"light\.normal: must be"),
    "open room": (lambda d: d["room"]["walls"].pop(2), r"room\.walls: the room is open"),
    "object outside": (lambda d: d["objects"][1].update(center=[12.5, 0.0, 0.0]), r"objects\[1\]: object outside the room"),
    "vertex outside": (lambda d: d["objects"][0]["vertices"][3].__setitem__(2, 6.0), r"objects\[0\]\.vertices\[3\]: object outside the room"),
    "non-finite albedo": (lambda d: d["room"]["walls"][1]["albedo"].__setitem__(0, float("nan")), r"room\.walls\[1\]\.albedo\[0\]: must be finite"),
    "negative albedo": (lambda d: d["objects"][0]["material"]["albedo"].__setitem__(2, -0.1), r"objects\[0\]\.material\.albedo\[2\]: must be in \[0\.0, 1\.0\]"),
    "infinite radiance": (lambda d: d["light"]["radiance"].__setitem__(1, float("inf")), r"light\.radiance\[1\]: must be finite"),
    "negative radiance": (lambda d: d["light"]["radiance"].__setitem__(1, -20.0), r"light\.radiance\[1\]: must be in \[0\.0, inf\]"),
    "light outside": (lambda d: d["light"].update(center=[5.0, 0.0, 5.5]), r"light: light outside the room"),
    "non-convex room": (lambda d: d["room"]["corners"].update(D=[5.0, 0.0]), r"room\.walls: the room must be a convex polygon"),
    "eye outside": (lambda d: d["cameras"]["far"].update(eye=[-20.0, 0.0, 0.0]), r"cameras\.far\.eye: the eye .* is outside the room"),
    "unknown camera": (lambda d: d["render"].update(camera="side"), r"render\.camera: no camera named 'side'"),
    "bad max depth": (lambda d: d["render"].update(max_depth=0), r"render\.max_depth: must be -1"),
    "unknown material": (lambda d: d["objects"][1]["material"].update(type="glass"), r"objects\[1\]\.material\.type: unknown material 'glass'"),
    "wrong format": (lambda d: d.update(format=2), r"format: unsupported format 2"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_validation_error_names_file_and_field(raw, tmp_path, case):
    import tomllib as _  # noqa: F401  (the bad file is written as TOML and read back through load_scene)

    edit, pattern = BAD[case]
    d = _edit(raw, edit)
    path = tmp_path / "bad.toml"
    path.write_text(_to_toml(d))
    with pytest.raises(SceneError, match=rf"^{path}: {pattern}"):
        load_scene(path)


def test_unreadable_and_invalid_files(tmp_path):
    with pytest.raises(SceneError, match=r"missing\.toml: cannot read"):
        load_scene(tmp_path / "missing.toml")
    p = tmp_path / "broken.toml"
    p.write_text("[room\nfloor_z = ")
    with pytest.raises(SceneError, match=r"broken\.toml: not valid TOML"):
        load_scene(p)


def _to_toml(d, prefix="") -> str:
    """A small TOML writer for the test's bad files (tables, arrays of tables, scalars, lists)."""

    def val(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return '"' + v + '"'
        if isinstance(v, float):
            return "nan" if v != v else ("inf" if v == float("inf") else ("-inf" if v == float("-inf") else repr(v)))
        if isinstance(v, list):
            return "[" + ", ".join(val(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {val(x)}" for k, x in v.items()) + " }"
        return str(v)

    lines, tables = [], []
    for k, v in d.items():
        if isinstance(v, dict) and not prefix.startswith("@inline"):
            tables.append((k, v))
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            tables.append((k, v))
        else:
            lines.append(f"{k} = {val(v)}")
    out = "\n".join(lines) + "\n"
    for k, v in tables:
        name = f"{prefix}.{k}" if prefix else k
        if isinstance(v, list):
            for item in v:
                out += f"\n[[{name}]]\n" + "\n".join(f"{a} = {val(b)}" for a, b in item.items()) + "\n"
        else:
            out += f"\n[{name}]\n" + _to_toml(v, name)
    return out


def test_a_room_surface_made_a_mirror_keeps_its_triangles_and_changes_the_hash(scene):
    """Room.mirrors makes the named surfaces mirrors (the rest, and every surface's triangles, as they were), is part
    of the content hash, and refuses a name no surface has."""
    from dataclasses import replace

    from mcrt.scene import Lambertian, Mirror

    edited = replace(scene, room=replace(scene.room, mirrors=(("floor", (0.7, 0.7, 0.7)),)))
    before, after = {s.name: s for s in scene.surfaces()}, {s.name: s for s in edited.surfaces()}
    assert after["floor"].material == Mirror(reflectance=(0.7, 0.7, 0.7))
    assert isinstance(before["floor"].material, Lambertian)
    assert all(np.array_equal(before[n].triangles, after[n].triangles) for n in before)
    assert all(before[n].material == after[n].material for n in before if n != "floor")
    assert edited.content_hash() != scene.content_hash()
    with pytest.raises(SceneError, match="no surface named 'wall_XY'"):
        replace(scene, room=replace(scene.room, mirrors=(("wall_XY", (1.0, 1.0, 1.0)),))).surfaces()
