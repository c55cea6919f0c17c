"""100 OpenCV views of a mesh made from NumPy arrays, in one call: depth, instance ids, barycentrics."""
import numpy as np

import hsr

# Two meshes from arrays: a unit box (instance 1) and a ground quad (instance 2).
box = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
quads = np.array([[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]])
ground = np.array([[-3.0, -0.5, -3.0], [3.0, -0.5, -3.0], [3.0, -0.5, 3.0], [-3.0, -0.5, 3.0]])
scene = hsr.Scene.from_arrays([box, ground], [quads, [[0, 1, 2, 3]]], instance_ids=[1, 2])

# OpenCV intrinsics and 100 world-to-camera poses on a circle, looking at the origin.
K = np.array([[500.0, 0.0, 319.5], [0.0, 500.0, 239.5], [0.0, 0.0, 1.0]])
poses = []
for a in np.linspace(0, 2 * np.pi, 100, endpoint=False):
    eye = np.array([4 * np.cos(a), 1.5, 4 * np.sin(a)])
    z = -eye / np.linalg.norm(eye)                     # forward
    x = np.cross(z, [0.0, -1.0, 0.0]); x /= np.linalg.norm(x)  # right (y is down)
    R = np.stack([x, np.cross(z, x), z])
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = R, -R @ eye
    poses.append(pose)
cameras = hsr.Camera.opencv(K, np.stack(poses), 640, 480, near=0.1, far=20.0)  # a list of 100

out = hsr.render(scene, cameras, outputs=("depth", "instance_id", "barycentric"))
print(out["depth"].shape, out["instance_id"].shape, out["barycentric"].shape)  # (100, 480, 640[, 3])
print("box pixels per view:", (out["instance_id"] == 1).sum(axis=(1, 2))[:5], "...")
