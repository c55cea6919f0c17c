// Files in and out: scene loading (mesh files, scene JSON, builtin:NAME) and the image writers
// of docs/conventions.md. Every writer writes a temporary file beside the target and renames it, so
// a failure never leaves half a file. Errors: InputError "file[:line]: problem".
#pragma once
#include <hsr/frame.hpp>
#include <hsr/scene.hpp>

#include <string>
#include <utility>
#include <vector>

namespace hsr {

/// Loads a scene: "builtin:NAME[?k=v&...]", a scene JSON (.json), OBJ, PLY, STL, OFF (own
/// loaders: double precision, file order, file:line errors) or anything else assimp reads
/// (glTF/GLB, ...). The returned scene is finalized.
Scene loadScene(const std::string& path);

/// One process's share of a scene, for processes that each hold only their own (hsr-mpi).
struct ScenePart {
  Scene scene;          // finalized (possibly empty); a scene JSON's camera and light
  bool whole = false;   // not a scene JSON of several meshes: `scene` is all of it
  size_t firstEntry = 0, entryCount = 0, entriesInFile = 0;  // the scene JSON's mesh entries it holds
};
/// Share `part` (0 <= part < parts) of the scene at `path`. A scene JSON of two or more mesh
/// entries is cut into `parts` contiguous runs of entries of about equal weight (a file's bytes; a
/// built-in entry weighs as the mean file) and only run `part` is loaded; its faces are the whole
/// scene's, in order, from the sum of the earlier runs' face counts on. Any other scene is loaded
/// whole (`whole`). Errors as loadScene's, except that an empty share is no error.
ScenePart loadScenePart(const std::string& path, int part, int parts);

/// Writers. The format follows the extension where there is a choice.
void writeColorPng(const Frame& frame, const std::string& path);
void writeFaceIds(const Frame& frame, const std::string& path);     // .png (24-bit id+1) or .npy (int32)
void writeDepth(const Frame& frame, const std::string& path);       // .npy .pfm .exr .f32
void writeDepthImage(const Frame& frame, const std::string& path);  // .png grey, near white
/// Frame::writes as a .png on a fixed scale (the same colour for the same count in every image):
/// black 0, then blue (1 write), green, yellow, orange, red, magenta, and white for 7 or more.
void writeOverdrawImage(const Frame& frame, const std::string& path);
void writeTextFile(const std::string& text, const std::string& path);

/// The files the writers above produce, for checking paths before any work is done.
enum class OutputKind : uint8_t { Color, FaceIds, Depth, DepthImage, OverdrawImage };
/// Throws InputError "path: ..." naming the allowed extensions when the writer for `kind` does
/// not know `path`'s extension (the writers check the same way).
void checkOutputPath(OutputKind kind, const std::string& path);

/// Writes `bytes` to `path` atomically (a temporary file `path.tmp-PID-N` beside it, then a
/// rename; a killed process may leave the temporary behind). Throws std::runtime_error,
/// also when `path` exists and is not a regular file (a device, FIFO, socket or directory is
/// never replaced).
void writeFileAtomic(const std::string& path, const void* bytes, size_t size);

/// Throws InputError "path: ..." when `path` is empty or names something that exists and is not
/// a regular file: what writeFileAtomic refuses, checked before any work is done.
void checkOutputTarget(const std::string& path);

/// All outputs or none. While a batch is alive on this thread, writeFileAtomic (so every writer
/// above) leaves each file in its temporary; commit() renames them all into place. A batch
/// destroyed without commit() (an exception) removes its temporaries, so no output is written.
class OutputBatch {
 public:
  OutputBatch();
  ~OutputBatch();
  OutputBatch(const OutputBatch&) = delete;
  OutputBatch& operator=(const OutputBatch&) = delete;
  /// Renames every staged file into place, in the order written. Throws std::runtime_error if a
  /// rename fails; the files not yet renamed are then removed.
  void commit();
  /// Called by writeFileAtomic: takes over temporary file `temp`, to become `target`.
  void stage(std::string temp, std::string target);

 private:
  std::vector<std::pair<std::string, std::string>> staged_;  // (temporary, target)
  OutputBatch* outer_;
};

}  // namespace hsr
