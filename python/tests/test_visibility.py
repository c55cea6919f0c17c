"""hsr.render's "visibility": per instance, the pixels covered alone equal those of rendering the
instance's triangles alone, the visible pixels those of the instance_id image, in one view or a
batch, on 1 or 2 threads."""
import numpy as np
import pytest

import hsr

FIELDS = ("instance_id", "px_count_all", "px_count_visib", "visib_fract")


def cameras(scene, width=160, height=120):
    """Three views around the scene and one whose near plane cuts through it, near and far given
    (a camera without them fits them to each scene, so a scene alone would get others)."""
    lo, hi = (np.asarray(b, float) for b in scene.bounds)
    centre, r = (lo + hi) / 2, float(np.linalg.norm(hi - lo))
    out = []
    for a in (0.7, 2.9, 4.6):
        eye = centre + r * np.array([np.cos(a), 0.45, np.sin(a)])
        out.append(hsr.Camera.look_at(eye, centre, width, height, fovy_deg=50, near=0.02 * r, far=4 * r))
    eye = centre + r * np.array([0.3, 0.3, 0.9])
    out.append(hsr.Camera.look_at(eye, centre, width, height, fovy_deg=60, near=0.95 * np.linalg.norm(eye - centre),
                                  far=4 * r))
    return out


def covered_alone(scene, faces, camera, threads):
    """Pixels covered by a render of the scene's triangles of `faces` alone (from_arrays)."""
    keep = np.isin(scene.triangle_faces, faces)
    alone = hsr.Scene.from_arrays(scene.vertices, scene.triangles[keep])
    return int((hsr.render(alone, camera, outputs="face_id", threads=threads)["face_id"] >= 0).sum())


def check(scene, threads):
    """Every instance's counts in every view against renders alone; the pixels covered but hidden."""
    face_instance = scene.face_instance_ids
    hidden = 0
    for camera in cameras(scene):
        out = hsr.render(scene, camera, outputs=("instance_id", "visibility"), threads=threads)
        vis = out["visibility"]
        assert vis.dtype.names == FIELDS
        assert vis.shape == (len(np.unique(face_instance)),)
        assert list(vis["instance_id"]) == sorted(set(face_instance.tolist()))
        for row in vis:
            faces = np.flatnonzero(face_instance == row["instance_id"])
            assert row["px_count_all"] == covered_alone(scene, faces, camera, threads)
            assert row["px_count_visib"] == (out["instance_id"] == row["instance_id"]).sum()
            all_ = row["px_count_all"]
            assert row["visib_fract"] == (row["px_count_visib"] / all_ if all_ else 0.0)
        hidden += int((vis["px_count_all"] - vis["px_count_visib"]).sum())
    return hidden


def objects(n, seed):
    """n boxes, randomly turned and placed so that they overlap and pass through each other."""
    rng = np.random.default_rng(seed)
    corners = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], float) - 0.5
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    tris = np.array([[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads])
    out = []
    for _ in range(n):
        rot, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        v = (corners * rng.uniform(0.4, 1.5, 3)) @ rot.T + rng.uniform(-1.5, 1.5, 3)
        out.append((v, tris))
    return out


@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("name", ["builtin:cubes", "builtin:clutter?n=10&detail=3", "builtin:city?blocks=2"])
def test_builtin_scenes_equal_each_instance_rendered_alone(name, threads):
    assert check(hsr.load(name), threads) > 0  # occlusion: the two counts differ somewhere


@pytest.mark.parametrize("threads", [1, 2])
def test_instances_of_several_meshes_apart(threads):
    objs = objects(12, 5)
    ids = [3 * (k % 4) + 1 for k in range(12)]  # meshes k, k + 4, k + 8 make one instance
    scene = hsr.Scene.from_arrays([v for v, _ in objs], [f for _, f in objs], instance_ids=ids)
    assert check(scene, threads) > 0


def test_a_batch_gives_each_views_counts():
    scene = hsr.load("builtin:clutter?n=10&detail=3")
    cams = cameras(scene)
    batch = hsr.render(scene, cams, outputs=("visibility",), threads=2)["visibility"]
    assert batch.shape == (len(cams), len(scene.meshes))
    for i, camera in enumerate(cams):
        one = hsr.render(scene, camera, outputs="visibility", threads=1)["visibility"]
        assert batch[i].tobytes() == one.tobytes()


def test_out_of_view_counts_zero():
    scene = hsr.load("builtin:cubes")
    camera = hsr.Camera.look_at((0, 0, 50), (0, 0, 100), 64, 48, near=0.1, far=100)  # looking away
    vis = hsr.render(scene, camera, outputs="visibility")["visibility"]
    assert len(vis) == len(scene.meshes)
    assert not vis["px_count_all"].any() and not vis["px_count_visib"].any() and not vis["visib_fract"].any()


def test_unknown_output_names_visibility_among_the_known():
    with pytest.raises(ValueError, match="visibility"):
        hsr.render(hsr.load("builtin:cubes"), hsr.Camera.look_at((4, 3, 5), (0, 0, 0), 32, 24), outputs="visible")
