# docs/distributed.md's five lines, under the guard a script that starts Dask worker processes needs.
import math, hsr, hsr.distributed
from distributed import Client

if __name__ == "__main__":
    client = Client(n_workers=2, threads_per_worker=1)          # a LocalCluster here; Client("tcp://scheduler:8786") on a cluster
    cameras = [hsr.Camera.look_at((900 + 1500 * math.cos(k / 16), 500, 900 + 1500 * math.sin(k / 16)), (900, 0, 900), 640, 480) for k in range(100)]
    views = hsr.distributed.render_views(client, "builtin:city", cameras, "out", outputs=("depth", "face_id"))
    rendered = sum(v["rendered"] for v in views)
    print(rendered, "views rendered,", len(views) - rendered, "complete already")
    client.close()
