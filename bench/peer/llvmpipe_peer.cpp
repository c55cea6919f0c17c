// hsr_peer_llvmpipe: renders one scene with hsr's z-buffer and with Mesa's llvmpipe (EGL
// surfaceless, OpenGL 4.5 core) under the same camera and conventions, times both in one
// interleaved run and checks that their face ids agree away from edges. Run by
// scripts/bench-peer.sh; its table is quoted in docs/benchmarks.md and the README.
#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <CLI/CLI.hpp>
#include <hsr/hsr.hpp>
#include <hsr/threads.hpp>

#include "gl_projection.hpp"
#include "id_compare.hpp"
#define GL_GLEXT_PROTOTYPES 1  // libOpenGL (GLVND) exports every OpenGL 4.5 core entry point
#include <GL/glcorearb.h>
#include <fmt/core.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace {

using hsr::InputError;

// --- Options ------------------------------------------------------------------------------

struct Options {
  std::string scene;
  std::string size = "1920x1080";
  int width = 0, height = 0;
  int frames = 10;
  int warmup = 2;
  double warmupSeconds = 1;  // warm-up iterations for at least this long too
  int threads = 0;                 // 0: all cores, for hsr and llvmpipe alike
  std::string raster = "default";  // hsr's z-buffer rasterizer: its default or a named one
  // hsr's buffers: by default those of the GL framebuffer (colour, face id, depth); every frame
  // is also timed with all four of hsr's buffers (triangle ids too).
  std::string outputs = "depth,face,color";
  bool json = false;
  bool markdownRow = false;
};

void parseSize(Options& o) {
  auto side = [](std::string_view s, int& out) {
    auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    return ec == std::errc() && end == s.data() + s.size() && out >= 1 && out <= 16384;
  };
  const size_t x = o.size.find_first_of("xX");
  const std::string_view text(o.size);
  if (x == std::string::npos || !side(text.substr(0, x), o.width) || !side(text.substr(x + 1), o.height))
    throw InputError("--size '" + o.size + "': expected WIDTHxHEIGHT, each 1 to 16384");
}

// --- EGL: a surfaceless OpenGL 4.5 core context on llvmpipe --------------------------------

// Owns the EGL display and context; everything GL below runs on the calling thread.
class EglContext {
 public:
  // llvmpipe reads LP_NUM_THREADS when the display is created, so the thread count is set first.
  explicit EglContext(int threads) {
    setenv("LP_NUM_THREADS", std::to_string(threads).c_str(), 1);
    // Software rendering even where a GPU exists: this benchmark is about llvmpipe.
    setenv("LIBGL_ALWAYS_SOFTWARE", "1", 1);
    setenv("GALLIUM_DRIVER", "llvmpipe", 1);

    const char* clientExtensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!has(clientExtensions, "EGL_MESA_platform_surfaceless"))
      fail("EGL has no EGL_MESA_platform_surfaceless (is Mesa's libegl-mesa0 installed?)");
    auto getPlatformDisplay =
        reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!getPlatformDisplay) fail("eglGetPlatformDisplayEXT is missing");
    display_ = getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    EGLint major = 0, minor = 0;
    if (display_ == EGL_NO_DISPLAY || !eglInitialize(display_, &major, &minor))
      fail("eglInitialize failed on the surfaceless platform");
    const char* extensions = eglQueryString(display_, EGL_EXTENSIONS);
    // No window, no pbuffer: the context renders into its own framebuffer object.
    if (!has(extensions, "EGL_KHR_surfaceless_context") || !has(extensions, "EGL_KHR_no_config_context"))
      fail("EGL lacks EGL_KHR_surfaceless_context or EGL_KHR_no_config_context");
    if (!eglBindAPI(EGL_OPENGL_API)) fail("eglBindAPI(EGL_OPENGL_API) failed");
    const EGLint attributes[] = {
        EGL_CONTEXT_MAJOR_VERSION,           4,       EGL_CONTEXT_MINOR_VERSION, 5, EGL_CONTEXT_OPENGL_PROFILE_MASK,
        EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    context_ = eglCreateContext(display_, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attributes);
    if (context_ == EGL_NO_CONTEXT) fail("no OpenGL 4.5 core context");
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_)) fail("eglMakeCurrent failed");
  }
  ~EglContext() { release(); }
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

 private:
  static bool has(const char* extensions, std::string_view name) {
    return extensions && std::string_view(extensions).find(name) != std::string_view::npos;
  }
  void release() {
    if (display_ == EGL_NO_DISPLAY) return;
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (context_ != EGL_NO_CONTEXT) eglDestroyContext(display_, context_);
    eglTerminate(display_);
    display_ = EGL_NO_DISPLAY;
  }
  // The constructor does not complete, so the destructor will not run: release here.
  [[noreturn]] void fail(const std::string& why) {
    const EGLint error = eglGetError();
    release();
    const std::string code = error == EGL_SUCCESS ? "" : fmt::format(" (EGL error 0x{:x})", unsigned(error));
    throw std::runtime_error("cannot create an llvmpipe OpenGL 4.5 context: " + why + code);
  }
  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
};

std::string glString(GLenum name) {
  const GLubyte* s = glGetString(name);
  return s ? reinterpret_cast<const char*>(s) : "";
}

void checkGl(const char* what) {
  if (GLenum e = glGetError(); e != GL_NO_ERROR)
    throw std::runtime_error(fmt::format("OpenGL error 0x{:x} in {}", unsigned(e), what));
}

// --- The OpenGL renderer ------------------------------------------------------------------

const char* kVertexShader = R"(#version 450 core
layout(location = 0) in vec3 position;  // hsr camera space, relative to the camera
layout(location = 1) in uint face;
layout(location = 2) in vec4 color;
uniform mat4 clipFromCamera;
flat out uint vFace;
flat out vec4 vColor;
void main() {
  gl_Position = clipFromCamera * vec4(position, 1.0);
  vFace = face;
  vColor = color;
}
)";

const char* kFragmentShader = R"(#version 450 core
flat in uint vFace;
flat in vec4 vColor;
layout(location = 0) out vec4 outColor;
layout(location = 1) out uint outFace;
void main() {
  outColor = vColor;
  outFace = vFace;
}
)";

GLuint compileShader(GLenum type, const char* source) {
  GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    throw std::runtime_error(std::string("shader compilation failed: ") + log);
  }
  return shader;
}

// One vertex of the static VBO: three per triangle, non-indexed, flat attributes repeated.
struct Vertex {
  float position[3];  // camera space: transformed in double, then rounded once
  uint32_t face;
  uint8_t color[4];
};
static_assert(sizeof(Vertex) == 20);

// The scene in GPU memory and a W x H framebuffer with colour (RGBA8), face id (R32UI, -1 =
// background) and depth (32-bit float, reversed); draws one frame per call.
class GlRenderer {
 public:
  GlRenderer(const hsr::Scene& scene, const hsr::Camera& camera) : width_(camera.width), height_(camera.height) {
    // Framebuffer.
    glCreateRenderbuffers(3, renderbuffers_);
    glNamedRenderbufferStorage(renderbuffers_[0], GL_RGBA8, width_, height_);
    glNamedRenderbufferStorage(renderbuffers_[1], GL_R32UI, width_, height_);
    glNamedRenderbufferStorage(renderbuffers_[2], GL_DEPTH_COMPONENT32F, width_, height_);
    glCreateFramebuffers(1, &framebuffer_);
    glNamedFramebufferRenderbuffer(framebuffer_, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, renderbuffers_[0]);
    glNamedFramebufferRenderbuffer(framebuffer_, GL_COLOR_ATTACHMENT1, GL_RENDERBUFFER, renderbuffers_[1]);
    glNamedFramebufferRenderbuffer(framebuffer_, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, renderbuffers_[2]);
    const GLenum drawBuffers[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(framebuffer_, 2, drawBuffers);
    if (glCheckNamedFramebufferStatus(framebuffer_, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw std::runtime_error("the framebuffer (RGBA8 + R32UI + DEPTH_COMPONENT32F) is incomplete");
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
    glViewport(0, 0, width_, height_);

    // Program.
    program_ = glCreateProgram();
    GLuint vs = compileShader(GL_VERTEX_SHADER, kVertexShader);
    GLuint fs = compileShader(GL_FRAGMENT_SHADER, kFragmentShader);
    glAttachShader(program_, vs);
    glAttachShader(program_, fs);
    glLinkProgram(program_);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint linked = 0;
    glGetProgramiv(program_, GL_LINK_STATUS, &linked);
    if (!linked) throw std::runtime_error("shader program link failed");
    glUseProgram(program_);
    const glm::mat4 clip(hsr::peer::clipFromCamera(camera));
    glUniformMatrix4fv(glGetUniformLocation(program_, "clipFromCamera"), 1, GL_FALSE, &clip[0][0]);

    // Geometry, uploaded once: every vertex transformed to camera space in double (as hsr does),
    // so float rounding happens on camera-relative coordinates.
    std::vector<glm::vec3> cameraPositions(scene.positions.size());
    for (size_t i = 0; i < scene.positions.size(); ++i)
      cameraPositions[i] = glm::vec3(camera.toCamera(scene.positions[i]));
    std::vector<Vertex> vertices;
    vertices.reserve(scene.triangles.size() * 3);
    for (const hsr::Triangle& t : scene.triangles) {
      const hsr::Rgba8 c = scene.faceColors[t.face];
      for (uint32_t v : t.v) {
        const glm::vec3& p = cameraPositions[v];
        vertices.push_back(Vertex{{p.x, p.y, p.z}, t.face, {c.r, c.g, c.b, c.a}});
      }
    }
    vertexCount_ = GLsizei(vertices.size());
    glCreateBuffers(1, &buffer_);
    glNamedBufferStorage(buffer_, GLsizeiptr(vertices.size() * sizeof(Vertex)), vertices.data(), 0);
    glCreateVertexArrays(1, &vertexArray_);
    glVertexArrayVertexBuffer(vertexArray_, 0, buffer_, 0, sizeof(Vertex));
    glEnableVertexArrayAttrib(vertexArray_, 0);
    glVertexArrayAttribFormat(vertexArray_, 0, 3, GL_FLOAT, GL_FALSE, offsetof(Vertex, position));
    glEnableVertexArrayAttrib(vertexArray_, 1);
    glVertexArrayAttribIFormat(vertexArray_, 1, 1, GL_UNSIGNED_INT, offsetof(Vertex, face));
    glEnableVertexArrayAttrib(vertexArray_, 2);
    glVertexArrayAttribFormat(vertexArray_, 2, 4, GL_UNSIGNED_BYTE, GL_TRUE, offsetof(Vertex, color));
    for (GLuint a = 0; a < 3; ++a) glVertexArrayAttribBinding(vertexArray_, a, 0);
    glBindVertexArray(vertexArray_);

    // State: hsr's conventions. Two-sided (no culling), reversed-Z with a strict test (ties keep
    // the triangle drawn first), depth in [0, 1] without OpenGL's [-1, 1] remapping.
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    glDisable(GL_CULL_FACE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_GREATER);
    checkGl("set-up");
  }
  ~GlRenderer() {
    glDeleteVertexArrays(1, &vertexArray_);
    glDeleteBuffers(1, &buffer_);
    glDeleteProgram(program_);
    glDeleteFramebuffers(1, &framebuffer_);
    glDeleteRenderbuffers(3, renderbuffers_);
  }
  GlRenderer(const GlRenderer&) = delete;
  GlRenderer& operator=(const GlRenderer&) = delete;

  // One frame: clear the three buffers, draw every triangle, wait until llvmpipe has finished.
  void drawFrame(hsr::Rgba8 background) {
    const GLfloat color[4] = {background.r / 255.0f, background.g / 255.0f, background.b / 255.0f,
                              background.a / 255.0f};
    const GLuint noFace[4] = {0xFFFFFFFFu, 0, 0, 0};  // reads back as int32 -1, hsr's background id
    const GLfloat farthest = 0.0f;                    // reversed-Z
    glClearBufferfv(GL_COLOR, 0, color);
    glClearBufferuiv(GL_COLOR, 1, noFace);
    glClearBufferfv(GL_DEPTH, 0, &farthest);
    glDrawArrays(GL_TRIANGLES, 0, vertexCount_);
    glFinish();
  }

  // Face ids (int32, -1 background) in hsr's row order (row 0 at the top).
  std::vector<int32_t> readFaceIds() {
    std::vector<int32_t> glRows(size_t(width_) * size_t(height_));
    glNamedFramebufferReadBuffer(framebuffer_, GL_COLOR_ATTACHMENT1);
    glReadPixels(0, 0, width_, height_, GL_RED_INTEGER, GL_UNSIGNED_INT, glRows.data());
    checkGl("reading face ids");
    return flipRows(glRows);
  }

  // Window depth (reversed, [0, 1]) in hsr's row order.
  std::vector<float> readDepth() {
    std::vector<float> glRows(size_t(width_) * size_t(height_));
    glReadPixels(0, 0, width_, height_, GL_DEPTH_COMPONENT, GL_FLOAT, glRows.data());
    checkGl("reading depth");
    return flipRows(glRows);
  }

 private:
  template <class T>
  std::vector<T> flipRows(const std::vector<T>& glRows) const {
    std::vector<T> rows(glRows.size());
    const size_t w = size_t(width_);
    for (int y = 0; y < height_; ++y)
      std::copy_n(glRows.begin() + ptrdiff_t(size_t(height_ - 1 - y) * w), w, rows.begin() + ptrdiff_t(size_t(y) * w));
    return rows;
  }

  int width_, height_;
  GLuint renderbuffers_[3] = {};
  GLuint framebuffer_ = 0, program_ = 0, buffer_ = 0, vertexArray_ = 0;
  GLsizei vertexCount_ = 0;
};

// --- The benchmark ------------------------------------------------------------------------

struct Timing {
  double median = 0, min = 0;
};
Timing summarize(std::vector<double> ms) {
  std::sort(ms.begin(), ms.end());
  const size_t n = ms.size();
  return {n % 2 ? ms[n / 2] : 0.5 * (ms[n / 2 - 1] + ms[n / 2]), ms.front()};
}

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

int run(Options& o) {
  parseSize(o);
  const int threads = o.threads > 0 ? o.threads : int(std::max(1u, std::thread::hardware_concurrency()));

  // The scene and the camera `hsr render` uses by default: the scene's own, else a framing.
  const hsr::Scene scene = hsr::loadScene(o.scene);
  const hsr::Bounds3 bounds = scene.bounds();
  const hsr::CameraSpec spec = scene.camera ? *scene.camera : hsr::frameBounds(bounds);
  const hsr::Camera camera = hsr::resolveCamera(spec, o.width, o.height, bounds, o.scene);
  hsr::RenderOptions hsrOptions;
  hsrOptions.shading = hsr::Shading::Flat;  // flat face colours, as the GL side draws
  hsrOptions.threads = threads;
  hsrOptions.outputs = hsr::parseFrameOutputs(o.outputs, "--outputs");
  if (!has(hsrOptions.outputs, hsr::FrameOutputs::FaceIds))
    throw InputError("--outputs '" + o.outputs + "': the comparison needs face ids (add face)");
  // Named rasterizers pin what is measured (halfspace: the scalar reference); "default" follows
  // hsr's own default, as `hsr render` and `hsr bench` do.
  if (o.raster != "default") hsrOptions.params["raster"] = o.raster;
  hsr::RenderOptions allOptions = hsrOptions;  // the same, with all four buffers
  allOptions.outputs = hsr::FrameOutputs::All;

  EglContext context(threads);
  const std::string renderer = glString(GL_RENDERER), version = glString(GL_VERSION);
  fmt::print(stderr, "GL_RENDERER: {}\nGL_VERSION: {}\n", renderer, version);
  if (!renderer.starts_with("llvmpipe"))
    throw std::runtime_error("the OpenGL renderer is '" + renderer + "', not llvmpipe");
  GlRenderer gl(scene, camera);

  // Interleaved: each iteration times one hsr frame, then one GL frame, so both see the same
  // machine load. The warm-up iterations (llvmpipe compiles its shaders) are not timed.
  // A third timing is hsr with all four of its buffers (triangle ids too, when --outputs leaves
  // some out), into a frame of its own, and the two hsr frames swap places every iteration (the
  // one right after the GL frame finds caches and idle threads as llvmpipe left them); a fourth
  // a floor for hsr: writing every buffer of --outputs once (the frame's clear, on the same
  // threads, into a frame of its own), no rendering at all.
  std::vector<double> hsrMs, glMs, allMs, writeMs;
  hsr::Frame frame, allFrame, written;
  written.allocate(o.width, o.height, hsrOptions.outputs);
  auto timed = [](auto&& work) {
    const auto start = std::chrono::steady_clock::now();
    work();
    return msSince(start);
  };
  // One algorithm object per configuration, kept across frames as GL keeps its context.
  hsr::Renderer hsrRenderer(scene, hsrOptions), allRenderer(scene, allOptions);
  auto iteration = [&](int i, bool record) {
    // (each reuses its frame's buffers, as GL reuses its FBO)
    auto renderHsr = [&] { return timed([&] { hsrRenderer.render(camera, frame); }); };
    auto renderAll = [&] { return timed([&] { allRenderer.render(camera, allFrame); }); };
    const bool hsrFirst = i % 2 == 0;
    const double firstMs = hsrFirst ? renderHsr() : renderAll();
    // hsr's pool threads spin a while after a job (kPoolSpin) before they sleep: not into
    // llvmpipe's time, where they would take a core from its threads.
    std::this_thread::sleep_for(2 * hsr::kPoolSpin);
    const double glFrameMs = timed([&] { gl.drawFrame(hsrOptions.background); });
    const double secondMs = hsrFirst ? renderAll() : renderHsr();
    const double writeFrameMs = timed([&] { written.clear(hsrOptions.background, threads); });
    if (record) {
      hsrMs.push_back(hsrFirst ? firstMs : secondMs);
      glMs.push_back(glFrameMs);
      allMs.push_back(hsrFirst ? secondMs : firstMs);
      writeMs.push_back(writeFrameMs);
    }
  };
  // Warm-up: o.warmup iterations, and more until o.warmupSeconds have passed (a new process on
  // this project's VMs runs slower for its first ~0.5 s; see docs/benchmarks.md).
  const auto warmupStart = std::chrono::steady_clock::now();
  int warmupIterations = 0;
  while (warmupIterations < o.warmup || msSince(warmupStart) < 1e3 * o.warmupSeconds)
    iteration(warmupIterations++, false);
  for (int i = 0; i < o.frames; ++i) iteration(warmupIterations + i, true);
  if (allFrame.faceId != frame.faceId)
    throw std::runtime_error("hsr's face ids differ between --outputs " + o.outputs + " and all four buffers");
  const Timing hsrTime = summarize(hsrMs), glTime = summarize(glMs), allTime = summarize(allMs),
               writeTime = summarize(writeMs);
  const double ratio = glTime.median / hsrTime.median, ratioAll = glTime.median / allTime.median;

  // Agreement of the last frames: face ids, then eye depth where the ids agree.
  const std::vector<int32_t> glIds = gl.readFaceIds();
  const hsr::peer::IdAgreement ids = hsr::peer::compareFaceIds(o.width, o.height, frame.faceId, glIds);
  // Eye depth, a check of the depth conventions: max |difference| / (far - near) over pixels with
  // equal ids away from edges (at grazing silhouettes snapping alone moves depth much more).
  const std::vector<float> glDepth = gl.readDepth();
  double depthMaxDiff = 0;
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x) {
      const size_t i = frame.index(x, y);
      if (glIds[i] < 0 || glIds[i] != frame.faceId[i] ||
          hsr::peer::isEdgePixel(o.width, o.height, frame.faceId, glIds, x, y))
        continue;
      const double glEyeDepth = hsr::peer::eyeDepthFromWindow(camera, glDepth[i]);
      depthMaxDiff = std::max(depthMaxDiff, std::abs(glEyeDepth - double(frame.depth[i])));
    }
  depthMaxDiff /= camera.far - camera.near;

  if (o.json) {
    nlohmann::json out;
    out["scene"] = o.scene;
    out["triangles"] = scene.triangles.size();
    out["width"] = o.width;
    out["height"] = o.height;
    out["threads"] = threads;
    out["hsr_raster"] = o.raster;
    out["hsr_outputs"] = hsr::frameOutputsName(hsrOptions.outputs);
    out["frames"] = o.frames;
    out["warmup"] = warmupIterations;
    out["gl_renderer"] = renderer;
    out["gl_version"] = version;
    out["hsr_median_ms"] = hsrTime.median;
    out["hsr_min_ms"] = hsrTime.min;
    out["gl_median_ms"] = glTime.median;
    out["gl_min_ms"] = glTime.min;
    out["ratio"] = ratio;
    out["hsr_all_outputs_median_ms"] = allTime.median;
    out["hsr_all_outputs_min_ms"] = allTime.min;
    out["ratio_all_outputs"] = ratioAll;
    out["frame_write_median_ms"] = writeTime.median;
    out["covered_pixels"] = ids.covered;
    out["equal_pixels"] = ids.equal;
    out["id_equal_fraction"] = ids.equalFraction();
    out["edge_mismatches"] = ids.edgeMismatches;
    out["nonedge_mismatches"] = ids.nonEdgeMismatches;
    nlohmann::json where = nlohmann::json::array();
    for (auto [x, y] : ids.firstNonEdge) where.push_back({x, y});
    out["first_nonedge_mismatches"] = where;
    out["depth_max_diff"] = depthMaxDiff;
    fmt::print("{}\n", out.dump(2));
  } else if (o.markdownRow) {
    fmt::print("| `{}` | {} | {:.1f} | {:.1f} | {:.1f} | {:.1f} | {:.2f} | {:.1f} | {:.1f} | {:.2f} | {:.3f}% | {} |\n",
               o.scene, scene.triangles.size(), hsrTime.median, hsrTime.min, glTime.median, glTime.min, ratio,
               writeTime.median, allTime.median, ratioAll, 100.0 * ids.equalFraction(), ids.nonEdgeMismatches);
  } else {
    fmt::print("{}: {} triangles, {}x{}, {} threads, {} frames interleaved ({} warm-up)\n", o.scene,
               scene.triangles.size(), o.width, o.height, threads, o.frames, warmupIterations);
    fmt::print("  hsr zbuffer ({} raster, outputs {}): median {:.2f} ms, min {:.2f} ms\n", o.raster,
               hsr::frameOutputsName(hsrOptions.outputs), hsrTime.median, hsrTime.min);
    fmt::print("  llvmpipe:    median {:.2f} ms, min {:.2f} ms\n", glTime.median, glTime.min);
    fmt::print("  ratio llvmpipe / hsr (medians): {:.3f}\n", ratio);
    fmt::print("  writing hsr's frame once (clear, no rendering): median {:.2f} ms\n", writeTime.median);
    fmt::print("  hsr with all four buffers (triangle ids too): median {:.2f} ms, ratio llvmpipe / hsr {:.3f}\n",
               allTime.median, ratioAll);
    fmt::print("  face ids: {} of {} covered pixels equal ({:.4f}%), {} mismatches on edges, {} elsewhere\n", ids.equal,
               ids.covered, 100.0 * ids.equalFraction(), ids.edgeMismatches, ids.nonEdgeMismatches);
    for (auto [x, y] : ids.firstNonEdge) {
      const size_t i = frame.index(x, y);
      fmt::print("    non-edge mismatch at ({}, {}): hsr face {}, llvmpipe face {}\n", x, y, frame.faceId[i], glIds[i]);
    }
    fmt::print("  eye depth where ids agree, away from edges: max |difference| = {:.3g} of far - near\n", depthMaxDiff);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app(
      "Peer benchmark: hsr's z-buffer against Mesa's llvmpipe (EGL surfaceless, OpenGL 4.5 core) on the "
      "same scene, camera and conventions; one interleaved run, medians, face-id agreement.",
      "hsr_peer_llvmpipe");
  Options o;
  app.add_option("scene", o.scene, "Mesh file, scene JSON or builtin:NAME[?k=v&...]")->type_name("SCENE")->required();
  app.add_option("--size", o.size, "Image size")->type_name("WxH")->capture_default_str();
  app.add_option("--frames", o.frames, "Timed frames of each renderer")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--warmup", o.warmup, "Untimed frames first")->check(CLI::Range(0, 100000))->capture_default_str();
  app.add_option("--warmup-time", o.warmupSeconds, "Untimed frames for at least this many seconds too")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  app.add_option("--threads", o.threads, "Threads of hsr and llvmpipe (LP_NUM_THREADS); 0 = all cores")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  app.add_option("--raster", o.raster,
                 "hsr's z-buffer rasterizer: hsr's default, or halfspace (the scalar reference) or scanline")
      ->check(CLI::IsMember({"default", "halfspace", "scanline"}))
      ->capture_default_str();
  app.add_option("--outputs", o.outputs,
                 "hsr's buffers (hsr bench --outputs): by default the GL framebuffer's attachments; each frame is "
                 "also timed with all four of hsr's buffers")
      ->type_name("LIST")
      ->capture_default_str();
  auto* json = app.add_flag("--json", o.json, "Print one JSON object");
  app.add_flag("--markdown-row", o.markdownRow,
               "Print one Markdown table row: scene, triangles, hsr ms median and min, llvmpipe ms median and min, "
               "ratio of medians, ms to write hsr's frame once (median), hsr ms median with all four buffers, its ratio, "
               "equal ids %, non-edge mismatches")
      ->excludes(json);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    return run(o);
  } catch (const InputError& e) {
    fmt::print(stderr, "hsr_peer_llvmpipe: {}\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    fmt::print(stderr, "hsr_peer_llvmpipe: {}\n", e.what());
    return 1;
  }
}
