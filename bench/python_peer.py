#!/usr/bin/python3
"""hsr's Python module against what pyrender does without a GPU: OpenGL from Python (Debian's
python3-opengl) on Mesa's llvmpipe through EGL's surfaceless platform (OSMesa when EGL
surfaceless is unavailable, said in the output). The same meshes and cameras on both sides:

  one view   1920x1080: hsr.render(scene, camera) vs one GL frame, depth + face ids each;
  a batch    100 views of 640x480: one hsr.render(scene, cameras) call vs 100 GL frames.

GL side, per view: the view's matrix as a uniform (the mesh uploaded once, world coordinates in
float32), a clear, one draw with the face id as a flat integer output (an R32UI attachment: the
exact form of pyrender's flat-colour ids), read-back of ids and depth with glReadPixels into new
NumPy arrays, rows flipped to put row 0 at the top, depth linearised to eye depth. Depth is a
32-bit float buffer with reversed-Z (glClipControl), hsr's own format, so the comparison tests
conventions rather than 24-bit precision. Timings are interleaved (hsr, then GL) and summarised
by medians. Agreement: face ids equal except on edge pixels (a 4-neighbour differs in either
image); eye depth where both show the same face: the largest relative difference and the number
of pixels over 1e-5. Memory: a batch's RSS growth in a new process (its first call, then a
second with the first one's arrays alive) against the arrays' bytes.

Run: PYTHONPATH=build/python /usr/bin/python3 bench/python_peer.py [--markdown]
"""
import argparse
import ctypes
import json
import os
import statistics
import subprocess
import sys
import time

import numpy as np

SCENES = ["builtin:sphere", "builtin:city", "/usr/share/assimp/models/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb"]


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scenes", nargs="*", default=SCENES, help="scenes (hsr.load names); default: sphere, city, a CAD model")
    p.add_argument("--size", default="1920x1080", help="the one view's size")
    p.add_argument("--batch-size", default="640x480", help="the batch views' size")
    p.add_argument("--views", type=int, default=100, help="views in the batch")
    p.add_argument("--frames", type=int, default=7, help="timed repetitions of each measurement (median)")
    p.add_argument("--threads", type=int, default=os.cpu_count(), help="hsr threads and LP_NUM_THREADS")
    p.add_argument("--platform", choices=["auto", "egl", "osmesa"], default="auto",
                   help="GL platform: EGL surfaceless, OSMesa, or EGL with OSMesa as the fallback")
    p.add_argument("--markdown", action="store_true", help="print Markdown table rows")
    p.add_argument("--json", action="store_true", help="print one JSON object per scene")
    p.add_argument("--memory-probe", action="store_true", help=argparse.SUPPRESS)  # (batch_memory's child)
    return p.parse_args()


def size_of(text):
    w, h = text.lower().split("x")
    return int(w), int(h)


# --- GL context ----------------------------------------------------------------------------

def egl_context():
    """A surfaceless EGL context (OpenGL 4.5 core) on Mesa; raises RuntimeError when unavailable."""
    from OpenGL import EGL
    from OpenGL.EGL.EXT.platform_base import eglGetPlatformDisplayEXT
    extensions = EGL.eglQueryString(EGL.EGL_NO_DISPLAY, EGL.EGL_EXTENSIONS) or b""
    if b"EGL_MESA_platform_surfaceless" not in extensions:
        raise RuntimeError("EGL has no EGL_MESA_platform_surfaceless")
    EGL_PLATFORM_SURFACELESS_MESA = 0x31DD
    display = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL.EGL_DEFAULT_DISPLAY, None)
    major, minor = EGL.EGLint(), EGL.EGLint()
    if not display or not EGL.eglInitialize(display, ctypes.pointer(major), ctypes.pointer(minor)):
        raise RuntimeError("eglInitialize failed on the surfaceless platform")
    if not EGL.eglBindAPI(EGL.EGL_OPENGL_API):
        raise RuntimeError("eglBindAPI(EGL_OPENGL_API) failed")
    attributes = (EGL.EGLint * 7)(EGL.EGL_CONTEXT_MAJOR_VERSION, 4, EGL.EGL_CONTEXT_MINOR_VERSION, 5,
                                   EGL.EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL.EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                   EGL.EGL_NONE)
    context = EGL.eglCreateContext(display, EGL.EGLConfig(), EGL.EGL_NO_CONTEXT, attributes)
    if not context:
        raise RuntimeError("no OpenGL 4.5 core context")
    if not EGL.eglMakeCurrent(display, EGL.EGL_NO_SURFACE, EGL.EGL_NO_SURFACE, context):
        raise RuntimeError("eglMakeCurrent failed")
    return ("egl surfaceless", display, context)


def osmesa_context():
    """An OSMesa context (OpenGL 4.5 core where Mesa offers it); its own buffer is unused."""
    from OpenGL import GL, arrays, osmesa
    attributes = arrays.GLintArray.asArray([osmesa.OSMESA_FORMAT, osmesa.OSMESA_RGBA, osmesa.OSMESA_DEPTH_BITS, 0,
                                            osmesa.OSMESA_PROFILE, osmesa.OSMESA_CORE_PROFILE,
                                            osmesa.OSMESA_CONTEXT_MAJOR_VERSION, 4,
                                            osmesa.OSMESA_CONTEXT_MINOR_VERSION, 5, 0])
    context = osmesa.OSMesaCreateContextAttribs(attributes, None)
    if not context:
        raise RuntimeError("OSMesaCreateContextAttribs failed")
    buffer = arrays.GLubyteArray.zeros((1, 1, 4))
    if not osmesa.OSMesaMakeCurrent(context, buffer, GL.GL_UNSIGNED_BYTE, 1, 1):
        raise RuntimeError("OSMesaMakeCurrent failed")
    return ("osmesa", context, buffer)


def make_context(platform, threads):
    """(platform name, handles); PYOPENGL_PLATFORM must be set before OpenGL.GL is imported,
    so falling back to OSMesa re-runs this script with --platform osmesa."""
    os.environ["LP_NUM_THREADS"] = str(threads)
    os.environ["LIBGL_ALWAYS_SOFTWARE"] = "1"
    os.environ["GALLIUM_DRIVER"] = "llvmpipe"
    os.environ["PYOPENGL_PLATFORM"] = "osmesa" if platform == "osmesa" else "egl"
    if platform == "osmesa":
        return osmesa_context()
    try:
        return egl_context()
    except Exception as e:  # noqa: BLE001 - any failure: say so, then OSMesa
        if platform == "egl":
            raise
        print(f"python_peer: EGL surfaceless unavailable ({e}); falling back to OSMesa", file=sys.stderr)
        args = [a for a in sys.argv[1:] if not a.startswith("--platform")]
        os.execv(sys.executable, [sys.executable, sys.argv[0], *args, "--platform", "osmesa"])


# --- The GL renderer -----------------------------------------------------------------------

VERTEX_SHADER = """#version 450 core
layout(location = 0) in vec3 position;
layout(location = 1) in uint face;
uniform mat4 clipFromWorld;
flat out uint vFace;
void main() { gl_Position = clipFromWorld * vec4(position, 1.0); vFace = face; }
"""
FRAGMENT_SHADER = """#version 450 core
flat in uint vFace;
layout(location = 0) out uint outFace;
void main() { outFace = vFace; }
"""


def clip_from_world(m, zero_to_one=True):
    """OpenGL clip coordinates from world for an hsr camera (Camera.resolve), for
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE) and reversed-Z (bench/peer/gl_projection.hpp):
    GL window x = hsr pixel x, window y = H - hsr pixel y, window depth = 1 - OpenGL's. Without
    glClipControl (zero_to_one False: OpenGL's [-1, 1] depth range) z is mapped so that the window
    depth is the same."""
    P, W, H = m["pixel_from_camera"], m["width"], m["height"]
    near, far = m["near"], m["far"]
    s = 1.0 if m["orthographic"] else near
    clip = np.array([P[0] * (2.0 / W) - P[3], P[3] - P[1] * (2.0 / H),
                     [0.0, 0.0, -s / (far - near), s * far / (far - near)], P[3]])
    if not zero_to_one:
        clip[2] = 2 * clip[2] - clip[3]
    return clip @ m["camera_from_world"]


def eye_depth(m, window):
    """Eye depth from reversed window depth (inverts clip_from_world's z); +inf where empty."""
    near, far = m["near"], m["far"]
    window = window.astype(np.float64)
    d = far - window * (far - near) if m["orthographic"] else near * far / (near + window * (far - near))
    return np.where(window > 0, d, np.inf).astype(np.float32)


class GlRenderer:
    """The scene uploaded once; a W x H framebuffer of face ids (R32UI) and depth (32F)."""

    def __init__(self, scene):
        from OpenGL import GL
        self.GL = GL
        vertices = scene.vertices[scene.triangles.reshape(-1)].astype(np.float32)
        faces = np.repeat(scene.triangle_faces.astype(np.uint32), 3)
        self.count = len(vertices)
        self.program = self._program()
        self.vao = GL.glGenVertexArrays(1)
        GL.glBindVertexArray(self.vao)
        self.buffers = GL.glGenBuffers(2)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, self.buffers[0])
        GL.glBufferData(GL.GL_ARRAY_BUFFER, vertices.nbytes, vertices, GL.GL_STATIC_DRAW)
        GL.glVertexAttribPointer(0, 3, GL.GL_FLOAT, GL.GL_FALSE, 0, None)
        GL.glEnableVertexAttribArray(0)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, self.buffers[1])
        GL.glBufferData(GL.GL_ARRAY_BUFFER, faces.nbytes, faces, GL.GL_STATIC_DRAW)
        GL.glVertexAttribIPointer(1, 1, GL.GL_UNSIGNED_INT, 0, None)
        GL.glEnableVertexAttribArray(1)
        self.location = GL.glGetUniformLocation(self.program, "clipFromWorld")
        # hsr's conventions: two-sided, reversed-Z with a strict test, depth in [0, 1] (PyOpenGL's
        # OSMesa platform does not find glClipControl: then clip_from_world maps z for [-1, 1]).
        self.zero_to_one = bool(GL.glClipControl)
        if self.zero_to_one:
            GL.glClipControl(GL.GL_LOWER_LEFT, GL.GL_ZERO_TO_ONE)
        GL.glDisable(GL.GL_CULL_FACE)
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glDepthFunc(GL.GL_GREATER)
        self.size = None
        self.draw_read_s = 0.0  # time in render() before linearisation, summed (the GL work alone)

    def _program(self):
        GL = self.GL
        program = GL.glCreateProgram()
        for kind, source in ((GL.GL_VERTEX_SHADER, VERTEX_SHADER), (GL.GL_FRAGMENT_SHADER, FRAGMENT_SHADER)):
            shader = GL.glCreateShader(kind)
            GL.glShaderSource(shader, source)
            GL.glCompileShader(shader)
            if not GL.glGetShaderiv(shader, GL.GL_COMPILE_STATUS):
                raise RuntimeError(GL.glGetShaderInfoLog(shader).decode())
            GL.glAttachShader(program, shader)
        GL.glLinkProgram(program)
        if not GL.glGetProgramiv(program, GL.GL_LINK_STATUS):
            raise RuntimeError(GL.glGetProgramInfoLog(program).decode())
        GL.glUseProgram(program)
        return program

    def _framebuffer(self, width, height):
        GL = self.GL
        if self.size == (width, height):
            return
        if self.size:
            GL.glDeleteFramebuffers(1, [self.fbo])
            GL.glDeleteRenderbuffers(2, self.renderbuffers)
        self.renderbuffers = GL.glGenRenderbuffers(2)
        GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, self.renderbuffers[0])
        GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, GL.GL_R32UI, width, height)
        GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, self.renderbuffers[1])
        GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, GL.GL_DEPTH_COMPONENT32F, width, height)
        self.fbo = GL.glGenFramebuffers(1)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.fbo)
        GL.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, GL.GL_RENDERBUFFER, self.renderbuffers[0])
        GL.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, GL.GL_DEPTH_ATTACHMENT, GL.GL_RENDERBUFFER, self.renderbuffers[1])
        if GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER) != GL.GL_FRAMEBUFFER_COMPLETE:
            raise RuntimeError("framebuffer R32UI + DEPTH_COMPONENT32F incomplete")
        GL.glReadBuffer(GL.GL_COLOR_ATTACHMENT0)
        GL.glViewport(0, 0, width, height)
        self.size = (width, height)

    def render(self, m):
        """One view (m: Camera.resolve): eye depth (float32, +inf empty) and face ids (int32, -1)."""
        GL = self.GL
        start = time.perf_counter()
        width, height = m["width"], m["height"]
        self._framebuffer(width, height)
        GL.glUniformMatrix4fv(self.location, 1, GL.GL_TRUE, clip_from_world(m, self.zero_to_one).astype(np.float32))
        GL.glClearBufferuiv(GL.GL_COLOR, 0, np.array([0xFFFFFFFF, 0, 0, 0], np.uint32))
        GL.glClearBufferfv(GL.GL_DEPTH, 0, np.array([0.0], np.float32))
        GL.glDrawArrays(GL.GL_TRIANGLES, 0, self.count)
        ids = np.empty((height, width), np.uint32)
        GL.glReadPixels(0, 0, width, height, GL.GL_RED_INTEGER, GL.GL_UNSIGNED_INT, ids)
        window = np.empty((height, width), np.float32)
        GL.glReadPixels(0, 0, width, height, GL.GL_DEPTH_COMPONENT, GL.GL_FLOAT, window)
        self.draw_read_s += time.perf_counter() - start
        return eye_depth(m, window[::-1]), ids[::-1].view(np.int32)


# --- Measurements --------------------------------------------------------------------------

def orbit_cameras(hsr, scene, count, width, height):
    """`count` look-at views around the scene's bounding sphere, at the default camera's distance."""
    base = scene.default_camera(width, height).resolve(scene)
    lo, hi = scene.bounds
    centre = (lo + hi) / 2
    eye = np.linalg.inv(base["camera_from_world"])[:3, 3]
    distance = np.linalg.norm(eye - centre)
    cams = []
    for i in range(count):
        azimuth, elevation = 2 * np.pi * i / count, 0.35 + 0.25 * np.sin(5.0 * i / count)  # above the ground
        direction = np.array([np.cos(elevation) * np.cos(azimuth), np.sin(elevation), np.cos(elevation) * np.sin(azimuth)])
        cams.append(hsr.Camera.look_at(centre + distance * direction, centre, width, height, fovy_deg=45.0))
    return cams


def edge_pixels(a, b):
    """Pixels where a 4-neighbour has another id in a or in b (bench/peer/id_compare.hpp)."""
    edge = np.zeros(a.shape, bool)
    for ids in (a, b):
        edge[:, 1:] |= ids[:, 1:] != ids[:, :-1]
        edge[:, :-1] |= ids[:, 1:] != ids[:, :-1]
        edge[1:, :] |= ids[1:, :] != ids[:-1, :]
        edge[:-1, :] |= ids[1:, :] != ids[:-1, :]
    return edge


class Agreement:
    def __init__(self):
        self.covered = self.equal = self.edge = self.non_edge = 0
        self.depth_rel = 0.0
        self.depth_over = 0  # pixels whose depths differ by more than 1e-5 relative

    def add(self, hsr_ids, hsr_depth, gl_ids, gl_depth):
        covered = (hsr_ids >= 0) | (gl_ids >= 0)
        same = covered & (hsr_ids == gl_ids)
        edge = edge_pixels(hsr_ids, gl_ids)
        self.covered += int(covered.sum())
        self.equal += int(same.sum())
        self.edge += int((covered & ~same & edge).sum())
        self.non_edge += int((covered & ~same & ~edge).sum())
        # Depth where both show the same face (edges included: with triangles smaller than a
        # pixel, as the sphere's at 640x480, nearly every pixel is an edge pixel).
        shown = same & (hsr_ids >= 0)
        if shown.any():
            rel = np.abs(gl_depth[shown].astype(np.float64) - hsr_depth[shown]) / hsr_depth[shown]
            self.depth_rel = max(self.depth_rel, float(rel.max()))
            self.depth_over += int((rel > 1e-5).sum())

    def as_dict(self):
        return {"covered": self.covered, "equal": self.equal, "edge_mismatches": self.edge,
                "non_edge_mismatches": self.non_edge, "depth_max_rel": self.depth_rel,
                "depth_over_1e-5": self.depth_over}


def rss_mb():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e6


def measure(hsr, gl, scene, cams, threads, frames):
    """Interleaved medians (ms) of hsr.render(scene, cams) and the GL frames of the same views,
    and their agreement on the last repetition."""
    batch = isinstance(cams, list)
    views = cams if batch else [cams]
    resolved = [c.resolve(scene) for c in views]
    hsr_ms, gl_ms, gl_draw_ms = [], [], []
    for rep in range(frames + 1):  # the first repetition warms both up, untimed
        t0 = time.perf_counter()
        out = hsr.render(scene, cams, outputs=("depth", "face_id"), threads=threads)
        t1 = time.perf_counter()
        time.sleep(0.001)  # hsr's pool threads stop spinning (kPoolSpin) before llvmpipe's turn
        gl.draw_read_s = 0.0
        t2 = time.perf_counter()
        gl_out = [gl.render(m) for m in resolved]
        t3 = time.perf_counter()
        if rep:
            hsr_ms.append(1e3 * (t1 - t0))
            gl_ms.append(1e3 * (t3 - t2))
            gl_draw_ms.append(1e3 * gl.draw_read_s)
    agreement = Agreement()
    for i, (gl_depth, gl_ids) in enumerate(gl_out):
        h_ids = out["face_id"][i] if batch else out["face_id"]
        h_depth = out["depth"][i] if batch else out["depth"]
        agreement.add(h_ids, h_depth, gl_ids, gl_depth)
    return statistics.median(hsr_ms), statistics.median(gl_ms), agreement, statistics.median(gl_draw_ms)


def batch_memory(name, args):
    """RSS growth (MB) of a first batch call in a new process, with its arrays alive; of a second
    call with the first one's arrays still alive; and the arrays' own bytes (MB)."""
    probe = [sys.executable, os.path.abspath(__file__), name, "--memory-probe", "--batch-size", args.batch_size,
             "--views", str(args.views), "--threads", str(args.threads)]
    return json.loads(subprocess.run(probe, check=True, capture_output=True, text=True).stdout)


def memory_probe(args):
    import hsr
    scene = hsr.load(args.scenes[0])
    cams = orbit_cameras(hsr, scene, args.views, *size_of(args.batch_size))
    hsr.render(scene, cams[:1], outputs=("depth", "face_id"), threads=args.threads)  # the code's pages, the pool's threads
    before = rss_mb()
    first = hsr.render(scene, cams, outputs=("depth", "face_id"), threads=args.threads)
    after_first = rss_mb()
    second = hsr.render(scene, cams, outputs=("depth", "face_id"), threads=args.threads)
    print(json.dumps({"first_mb": after_first - before, "second_mb": rss_mb() - after_first,
                      "outputs_mb": sum(a.nbytes for a in second.values()) / 1e6}))
    del first


def main():
    args = parse_args()
    if args.memory_probe:
        return memory_probe(args)
    platform = make_context(args.platform, args.threads)
    from OpenGL import GL
    import hsr
    renderer = GL.glGetString(GL.GL_RENDERER).decode()
    version = GL.glGetString(GL.GL_VERSION).decode()
    print(f"GL platform: {platform[0]}; GL_RENDERER: {renderer}; GL_VERSION: {version}", file=sys.stderr)
    if "llvmpipe" not in renderer:
        raise SystemExit(f"python_peer: the GL renderer is '{renderer}', not llvmpipe")
    one_w, one_h = size_of(args.size)
    batch_w, batch_h = size_of(args.batch_size)
    if args.markdown:
        print(f"| scene | triangles | 1 view {args.size}: hsr ms | GL ms (draw + read) | ratio | ids equal % | non-edge mismatches "
              f"| depth max rel (pixels > 1e-5) | {args.views} views {args.batch_size}: hsr ms | GL ms (draw + read) | ratio | ids equal % "
              f"| non-edge mismatches | depth max rel (pixels > 1e-5) | batch RSS growth, 1st and 2nd call / outputs MB |")
        print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name in args.scenes:
        scene = hsr.load(name)
        gl = GlRenderer(scene)
        one = measure(hsr, gl, scene, scene.default_camera(one_w, one_h), args.threads, args.frames)
        cams = orbit_cameras(hsr, scene, args.views, batch_w, batch_h)
        many = measure(hsr, gl, scene, cams, args.threads, max(1, args.frames // 2))
        memory = batch_memory(name, args)
        row = {"scene": name, "triangles": scene.triangle_count, "threads": args.threads, "platform": platform[0],
               "gl_renderer": renderer,
               "one": {"size": args.size, "hsr_ms": one[0], "gl_ms": one[1], "ratio": one[1] / one[0],
                       "gl_draw_read_ms": one[3], **one[2].as_dict()},
               "batch": {"views": args.views, "size": args.batch_size, "hsr_ms": many[0], "gl_ms": many[1],
                         "gl_draw_read_ms": many[3],
                         "ratio": many[1] / many[0], **many[2].as_dict(), "rss_growth_first_mb": memory["first_mb"],
                         "rss_growth_second_mb": memory["second_mb"], "outputs_mb": memory["outputs_mb"]}}
        if args.json:
            print(json.dumps(row))
        elif args.markdown:
            o, b = row["one"], row["batch"]
            short = os.path.basename(name)
            print(f"| `{short}` | {row['triangles']} | {o['hsr_ms']:.1f} | {o['gl_ms']:.1f} ({o['gl_draw_read_ms']:.1f}) | {o['ratio']:.1f} "
                  f"| {100 * o['equal'] / max(1, o['covered']):.3f} | {o['non_edge_mismatches']} | {o['depth_max_rel']:.1e} ({o['depth_over_1e-5']}) "
                  f"| {b['hsr_ms']:.0f} | {b['gl_ms']:.0f} ({b['gl_draw_read_ms']:.0f}) | {b['ratio']:.1f} | {100 * b['equal'] / max(1, b['covered']):.3f} "
                  f"| {b['non_edge_mismatches']} | {b['depth_max_rel']:.1e} ({b['depth_over_1e-5']}) | {b['rss_growth_first_mb']:.0f}, {b['rss_growth_second_mb']:.0f} / {b['outputs_mb']:.0f} |")
        else:
            for label, r in (("1 view " + args.size, row["one"]), (f"{args.views} views {args.batch_size}", row["batch"])):
                print(f"{name}, {label}: hsr {r['hsr_ms']:.1f} ms, GL {r['gl_ms']:.1f} ms ({r['gl_draw_read_ms']:.1f} drawing and "
                      f"reading back), ratio {r['ratio']:.1f}; ids "
                      f"{r['equal']}/{r['covered']} equal, {r['edge_mismatches']} edge and {r['non_edge_mismatches']} "
                      f"non-edge mismatches; depth max rel {r['depth_max_rel']:.2e} ({r['depth_over_1e-5']} pixels over 1e-5)")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
