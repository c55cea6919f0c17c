import hsr
scene = hsr.load("builtin:cubes")
camera = hsr.Camera.look_at(eye=(4, 3, 5), target=(0, 0, 0), width=640, height=480)
out = hsr.render(scene, camera, outputs=("depth", "face_id", "instance_id"))
print(out["depth"].shape, out["depth"].min(), out["face_id"].max(), sorted(set(out["instance_id"].flat)))
