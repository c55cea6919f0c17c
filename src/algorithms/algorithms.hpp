// The visibility algorithms, one function each, registered in render.cpp. Each fills the whole
// Frame (visibility buffer + statistics) from a finalized scene and a resolved camera. render()
// hands it sized but not cleared (Frame::allocate): an algorithm writes every pixel of the
// buffers present, or calls Frame::clear() first.
#pragma once
#include <hsr/render.hpp>

namespace hsr::algo {

void zbuffer(const Scene&, const Camera&, const RenderOptions&, Frame&);  // zbuffer.cpp
void raycast(const Scene&, const Camera&, const RenderOptions&, Frame&);  // raycast.cpp

/// Statistics of a frame before it is drawn: image size, faces and triangles of the scene
/// (render.cpp; render() starts every frame's statistics so, as does the occlusion buffer).
Stats frameStats(const Scene& scene, const Camera& camera);

/// Throws InputError unless the camera's image size is in 1..kMaxImageSize and the depth format
/// suits the camera (render.cpp; also checked by the occlusion buffer).
void checkImage(const Camera& camera, DepthFormat format);

/// Whether the occlusion buffer culls this scene mesh by mesh (occlusion.cpp: at least 64
/// meshes, a perspective camera, HSR_MESH_CULLING not off). zbuffer's depth-only frames of such
/// scenes go through an occlusion buffer and its depthImage (the same bits).
bool meshCullingApplies(const Scene& scene, const Camera& camera);
/// Whether a frame with ids of this scene may gain from mesh culling's first pass (algo::cullMeshes):
/// meshCullingApplies, and the scene holds enough triangles for the pass over every tile of the
/// image (occlusion.cpp, kFrameWaitingPerTile); cullMeshes then decides by the meshes it can test.
bool meshCullingPaysForFrame(const Scene& scene, const Camera& camera);

}  // namespace hsr::algo
