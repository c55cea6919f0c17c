// What a render is asked for: the algorithm and its parameters, the depth format, the outputs,
// culling, shading, threads and the tiled z-buffer's switches. Every floor of the library reads
// these; the Renderer that acts on them is render.hpp's.
#pragma once
#include <hsr/common.hpp>
#include <hsr/depth_format.hpp>
#include <hsr/frame.hpp>

#include <cstdint>
#include <map>
#include <string>

namespace hsr {

enum class Cull : uint8_t { None, Back, Front };
enum class Shading : uint8_t { Flat, Lambert, FaceId };

/// The tiled z-buffer's and the occlusion buffer's optimisations, each of which leaves every image
/// and stored depth the same bits: all on by default, turned off to test that and to measure
/// what each saves (the command line's --switch-off NAME; docs/kernel.md).
struct TiledSwitches {
  bool deferBackFaces = true;  // defer-back-faces: with cull none, back faces set up after the front faces
  bool deferClusters = true;   // defer-clusters: whole clusters facing away deferred (with cull back: culled)
  bool meshCulling = true;     // mesh-culling: scenes of many meshes culled mesh by mesh (docs/occlusion.md)
  bool backgroundPump = true;  // background-pump: idle tiles' background streamed between the kernel's blocks
};
/// The switches' names, as --switch-off takes them.
inline constexpr const char* kTiledSwitchNames[] = {"defer-back-faces", "defer-clusters", "mesh-culling",
                                                    "background-pump"};
/// Turns off the switch `name` (kTiledSwitchNames); InputError for another name.
void switchOff(TiledSwitches& switches, const std::string& name);

struct RenderOptions {
  std::string algorithm = "zbuffer";
  /// The algorithm's own parameters, name -> value as text (`--param name=value`); those not
  /// given take their defaults (`hsr algorithms` lists them).
  std::map<std::string, std::string> params;
  DepthFormat depthFormat;                // default f32:reversed
  FrameOutputs outputs = FrameOutputs::All;  // what is resolved into the Frame (frame.hpp)
  Cull cull = Cull::None;
  Shading shading = Shading::Lambert;
  Rgba8 background{0, 0, 0, 255};
  int threads = 0;                        // 0: all cores
  bool verify = false;                    // also render the reference and count wrong pixels
  bool countWrites = false;               // fill Frame::writes: fragments written per pixel
  TiledSwitches tiled;                    // zbuffer raster=tiled: its optimisations, all on
};

}  // namespace hsr
