// `hsr batch`: renders the views a JSON Lines manifest lists, all of them or one shard, into a
// folder: each view's files written atomically, then one index line naming them with their
// SHA-256. A view already complete and verified is skipped, so a killed run resumes. What a Slurm
// array task or a Kubernetes Indexed Job pod runs (docs/distributed.md); set up by apps/main.cpp.
#include <hsr/hsr.hpp>

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

#include "commands.hpp"
#include "flags.hpp"
#include "sha256.hpp"

namespace hsr::cli {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;  // keys sorted: dump() is the canonical text a view's digest is taken of

struct BatchFlags {
  std::string manifest, out, shard;
  int threads = 0;
  bool quiet = false, verbose = false;
};

// ---------------------------------------------------------------------------------------------
// The manifest: one view per line (docs/distributed.md "The manifest").

// What a view may ask for: each output is written from one frame buffer in one of its formats.
enum class OutputKind { Depth, FaceId, InstanceId, Barycentric, Color, DepthImage };
struct OutputType {
  const char* name;
  OutputKind kind;
  std::vector<std::string> formats;  // file extensions, the default first
  hsr::FrameOutputs needs;           // the buffers the frame must resolve for it
};
const OutputType kOutputTypes[] = {
    {"depth", OutputKind::Depth, {"npy", "pfm", "exr", "f32"}, hsr::FrameOutputs::DepthOnly},
    {"face_id", OutputKind::FaceId, {"npy", "png"}, hsr::FrameOutputs::FaceIds},
    {"instance_id", OutputKind::InstanceId, {"npy", "png"}, hsr::FrameOutputs::FaceIds},
    {"barycentric", OutputKind::Barycentric, {"npy"}, hsr::FrameOutputs::TriangleIds},
    {"color", OutputKind::Color, {"png"}, hsr::FrameOutputs::Color},
    {"depth_image", OutputKind::DepthImage, {"png"}, hsr::FrameOutputs::DepthOnly},
};
const char* const kManifestKeys[] = {"id", "scene", "camera", "size", "outputs", "algorithm", "params",
                                     "depth_format"};

struct ViewOutput {
  const OutputType* type;
  std::string file;  // in the output folder: ID.NAME.EXT
};

struct View {
  std::string where;  // "MANIFEST:LINE", what every message about the view starts with
  std::string id;
  std::string scene;  // as loadScene takes it: builtin:..., or a path resolved against the manifest's folder
  std::optional<hsr::CameraSpec> camera;
  std::optional<ImageSize> size;
  std::string algorithm = "zbuffer";
  std::map<std::string, std::string> params;
  std::optional<hsr::DepthFormat> depthFormat;
  std::vector<ViewOutput> outputs;
  std::string digest;  // SHA-256 of the line's canonical JSON: a view whose line changed is rendered again

  // Views with the same key share one Renderer.
  std::string rendererKey() const {
    std::string key = algorithm;
    for (const auto& [name, value] : params) key += "\n" + name + "=" + value;
    return key;
  }
};

// A library error in the manifest's terms: a keyed error names the key of the line that sets it.
std::string manifestWording(const hsr::InputError& error) {
  switch (error.setting()) {
    case hsr::Setting::Algorithm: return error.worded("algorithm");
    case hsr::Setting::Param: return error.worded("params");
    case hsr::Setting::Size: return error.worded("size");
    case hsr::Setting::DepthFormat: return error.worded("depth_format");
    default: return cliMessage(error);  // plain, or a setting only a flag sets (--max-memory)
  }
}

std::string joinedNames(const OutputType* types, size_t count) {
  std::string names;
  for (size_t i = 0; i < count; ++i) names += (i ? ", " : "") + std::string(types[i].name);
  return names;
}

// "v0001": letters, digits, '_', '-' and '.', not starting with '.': a file name part on any system.
bool validId(const std::string& id) {
  if (id.empty() || id.size() > 128 || id[0] == '.') return false;
  return std::all_of(id.begin(), id.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
  });
}

std::string requiredString(const Json& line, const char* key, const std::string& where) {
  if (!line.contains(key)) throw InputError(fmt::format("{}: '{}' is missing", where, key));
  if (!line[key].is_string()) throw InputError(fmt::format("{}: '{}' must be a string", where, key));
  return line[key].get<std::string>();
}

// The scene as loadScene takes it, checked to exist: a built-in's name, or a file.
std::string checkedScene(const std::string& scene, const fs::path& manifestFolder, const std::string& where) {
  if (scene.rfind("builtin:", 0) == 0) {
    const std::string name = scene.substr(8, scene.find('?') - 8);  // npos - 8: to the end
    const auto& known = hsr::builtinScenes();
    if (std::none_of(known.begin(), known.end(), [&](const hsr::BuiltinInfo& b) { return b.name == name; }))
      throw InputError(fmt::format("{}: scene '{}': no such built-in scene ('hsr scenes' lists them)", where, scene));
    return scene;
  }
  const fs::path path = fs::path(scene).is_absolute() ? fs::path(scene) : manifestFolder / scene;
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status))
    throw InputError(fmt::format("{}: scene '{}': no such file ({})", where, scene, path.string()));
  if (!fs::is_regular_file(status))
    throw InputError(fmt::format("{}: scene '{}': not a regular file ({})", where, scene, path.string()));
  return path.string();
}

std::vector<ViewOutput> parseOutputs(const Json& line, const std::string& id, const std::string& where) {
  constexpr size_t kTypes = std::size(kOutputTypes);
  const std::string known = joinedNames(kOutputTypes, kTypes);
  if (!line.contains("outputs")) throw InputError(fmt::format("{}: 'outputs' is missing (any of {})", where, known));
  const Json& list = line["outputs"];
  if (!list.is_array() || list.empty())
    throw InputError(fmt::format("{}: 'outputs' must be a non-empty array of names such as \"depth\" or "
                                 "\"face_id.png\" (names: {})", where, known));
  std::vector<ViewOutput> outputs;
  for (const Json& item : list) {
    if (!item.is_string()) throw InputError(fmt::format("{}: outputs: {} is not a string", where, item.dump()));
    const std::string text = item.get<std::string>();
    const size_t dot = text.find('.');
    const std::string name = text.substr(0, dot);
    const auto* type = std::find_if(std::begin(kOutputTypes), std::end(kOutputTypes),
                                    [&](const OutputType& t) { return name == t.name; });
    if (type == std::end(kOutputTypes))
      throw InputError(fmt::format("{}: outputs: unknown output '{}' (known: {})", where, text, known));
    const std::string format = dot == std::string::npos ? type->formats.front() : text.substr(dot + 1);
    if (std::find(type->formats.begin(), type->formats.end(), format) == type->formats.end()) {
      std::string formats;
      for (const std::string& f : type->formats) formats += (formats.empty() ? "" : ", ") + f;
      throw InputError(fmt::format("{}: outputs: '{}': {} is written as {}", where, text, name, formats));
    }
    if (std::any_of(outputs.begin(), outputs.end(), [&](const ViewOutput& o) { return o.type == type; }))
      throw InputError(fmt::format("{}: outputs: {} is asked for twice", where, name));
    outputs.push_back({type, id + "." + name + "." + format});
  }
  return outputs;
}

std::map<std::string, std::string> parseParams(const Json& line, const std::string& where) {
  std::map<std::string, std::string> params;
  if (!line.contains("params")) return params;
  if (!line["params"].is_object())
    throw InputError(where + ": 'params' must be an object of KEY: VALUE ('hsr algorithms' lists them)");
  for (const auto& [key, value] : line["params"].items()) {
    if (!value.is_string() && !value.is_number() && !value.is_boolean())
      throw InputError(fmt::format("{}: params: '{}' must be a string, number or boolean", where, key));
    params[key] = value.is_string() ? value.get<std::string>() : value.dump();
  }
  return params;
}

// Checks what resolveCamera checks without the scene: its bounds only choose near and far when
// the camera gives none, so a missing plane is given a value that cannot fail on its own.
void checkCamera(hsr::CameraSpec spec, ImageSize size, const std::string& where) {
  if (spec.far && !spec.near) spec.near = *spec.far > 0 ? *spec.far * 0.5 : *spec.far - 1;
  hsr::resolveCamera(spec, size.width, size.height, hsr::Bounds3{}, where);
}

// One line of the manifest as a view, every key checked (InputError "MANIFEST:LINE: problem").
View parseView(const std::string& text, const std::string& where, const fs::path& manifestFolder) {
  // 1. JSON, one object, known keys.
  Json line;
  try {
    line = Json::parse(text);
  } catch (const Json::parse_error& e) {  // "... parse error at line 1, column C: the problem"
    const std::string what = e.what();
    const size_t colon = what.find(": ", what.find("column"));
    throw InputError(fmt::format("{}: not valid JSON at column {}: {}", where, e.byte,
                                 colon == std::string::npos ? what : what.substr(colon + 2)));
  } catch (const Json::exception& e) {  // a number beyond a double's range
    throw InputError(fmt::format("{}: not valid JSON: {}", where, e.what()));
  }
  if (!line.is_object()) throw InputError(where + ": expected one JSON object per line");
  for (const auto& item : line.items())
    if (std::find(std::begin(kManifestKeys), std::end(kManifestKeys), item.key()) == std::end(kManifestKeys))
      throw InputError(fmt::format("{}: unknown key '{}' (keys: id, scene, camera, size, outputs, algorithm, "
                                   "params, depth_format)", where, item.key()));
  // 2. What the view is: its id, scene and outputs.
  View v;
  v.where = where;
  v.id = requiredString(line, "id", where);
  if (!validId(v.id))
    throw InputError(fmt::format("{}: id '{}': expected 1 to 128 letters, digits, '_', '-' or '.', not "
                                 "starting with '.'", where, v.id));
  v.scene = checkedScene(requiredString(line, "scene", where), manifestFolder, where);
  v.outputs = parseOutputs(line, v.id, where);
  // 3. How it is seen: camera and size.
  if (line.contains("camera")) v.camera = hsr::parseCameraJson(line["camera"].dump(), where);
  if (line.contains("size")) v.size = parseSize(line["size"].is_string() ? line["size"].get<std::string>()
                                                                          : line["size"].dump(), where + ": size");
  if (!v.size && v.camera && v.camera->width) v.size = ImageSize{*v.camera->width, *v.camera->height};
  if (!v.size)
    throw InputError(where + ": 'size' is missing: give \"size\": \"WxH\" (or a camera with width and height)");
  if (v.camera) checkCamera(*v.camera, *v.size, where);
  // 4. How it is rendered: algorithm, parameters, depth format.
  try {
    if (line.contains("algorithm")) v.algorithm = requiredString(line, "algorithm", where);
    const hsr::AlgorithmInfo* algorithm = hsr::findAlgorithm(v.algorithm);
    if (!algorithm)
      throw InputError(fmt::format("{}: algorithm '{}': unknown (known: {})", where, v.algorithm, algorithmNames()));
    v.params = parseParams(line, where);
    hsr::resolveParams(*algorithm, v.params);
    if (line.contains("depth_format"))
      v.depthFormat = hsr::DepthFormat::parse(requiredString(line, "depth_format", where));
  } catch (const hsr::InputError& e) {
    if (e.setting() == hsr::Setting::None) throw;
    throw InputError(where + ": " + manifestWording(e));
  }
  v.digest = sha256Hex(line.dump());
  return v;
}

// Every view of the manifest, every line checked before anything is rendered: a bad line stops
// every shard alike, with nothing written. Blank lines are allowed and counted.
std::vector<View> readManifest(const std::string& manifest) {
  const std::string text = readTextFile(manifest);
  const fs::path folder = fs::path(manifest).parent_path();
  std::vector<View> views;
  std::unordered_map<std::string, size_t> lineOfId;
  size_t start = 0;
  for (size_t number = 1; start < text.size(); ++number) {
    const size_t end = std::min(text.find('\n', start), text.size());
    std::string line = text.substr(start, end - start);
    start = end + 1;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const std::string where = fmt::format("{}:{}", manifest, number);
    View view = parseView(line, where, folder);
    if (auto [it, fresh] = lineOfId.emplace(view.id, number); !fresh)
      throw InputError(fmt::format("{}: id '{}' is also the id of line {}", where, view.id, it->second));
    views.push_back(std::move(view));
  }
  if (views.empty()) throw InputError(manifest + ": no views (one JSON object per line)");
  return views;
}

// ---------------------------------------------------------------------------------------------
// Shards: contiguous blocks of the manifest, so that a manifest ordered by scene gives each shard
// few scenes to load.

constexpr uint64_t kMaxShards = 1'000'000'000;  // V * N stays within 64 bits for any manifest

struct Shard {
  uint64_t index = 0, count = 1;
  std::string indexFile() const { return fmt::format("index-{}-of-{}.jsonl", index, count); }
};

Shard parseShard(const std::string& text) {
  Shard shard;
  if (text.empty()) return shard;
  const size_t slash = text.find('/');
  auto number = [](std::string_view s, uint64_t& out) {
    auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    return !s.empty() && ec == std::errc() && end == s.data() + s.size();
  };
  if (slash == std::string::npos || !number(std::string_view(text).substr(0, slash), shard.index) ||
      !number(std::string_view(text).substr(slash + 1), shard.count) || shard.count == 0 ||
      shard.count > kMaxShards || shard.index >= shard.count)
    throw InputError(fmt::format("--shard '{}': expected I/N, shard I of N counted from 0 (0 <= I < N <= {}), "
                                 "e.g. $SLURM_ARRAY_TASK_ID/8", text, kMaxShards));
  return shard;
}

// Views [V*I/N, V*(I+1)/N): sizes differ by one at most, and a view's shard depends only on its
// position in the manifest.
std::span<const View> viewsOf(const std::vector<View>& views, Shard shard) {
  const auto first = size_t(views.size() * shard.index / shard.count);
  const auto last = size_t(views.size() * (shard.index + 1) / shard.count);
  return std::span<const View>(views).subspan(first, last - first);
}

// ---------------------------------------------------------------------------------------------
// The index: one JSON line per view written, appended after its files were renamed into place.

struct FileRecord {
  std::string output, file, sha256;
  uint64_t bytes = 0;
};
struct IndexEntry {
  std::string digest;  // the view's line, as View::digest
  std::vector<FileRecord> files;
};
struct Index {
  std::unordered_map<std::string, std::vector<IndexEntry>> byId;  // in the order read
  size_t ignoredLines = 0;  // torn by a kill, or not an index line
};

std::optional<std::string> sha256OfFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  Sha256 hash;
  std::vector<char> chunk(size_t(1) << 20);
  while (in) {
    in.read(chunk.data(), std::streamsize(chunk.size()));
    hash.update(chunk.data(), size_t(in.gcount()));
  }
  if (in.bad()) return std::nullopt;
  return hash.hexDigest();
}

std::optional<std::pair<std::string, IndexEntry>> parseIndexLine(const std::string& text) {
  const Json line = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  try {
    if (!line.is_object() || !line.at("files").is_array()) return std::nullopt;
    IndexEntry entry{line.at("view_sha256").get<std::string>(), {}};
    for (const Json& f : line.at("files"))
      entry.files.push_back({f.at("output").get<std::string>(), f.at("file").get<std::string>(),
                             f.at("sha256").get<std::string>(), f.at("bytes").get<uint64_t>()});
    return std::pair{line.at("id").get<std::string>(), std::move(entry)};
  } catch (const Json::exception&) {
    return std::nullopt;
  }
}

// Every index file of the folder (any shard count's): a view another sharding completed counts.
// A line counts only when whole: a last line without its newline was torn by a kill.
Index readIndexes(const fs::path& dir) {
  Index index;
  std::vector<fs::path> files;
  for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (e.is_regular_file() && name.rfind("index-", 0) == 0 && e.path().extension() == ".jsonl")
      files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  for (const fs::path& file : files) {
    const std::string text = readTextFile(file.string());
    size_t start = 0;
    for (size_t end; (end = text.find('\n', start)) != std::string::npos; start = end + 1) {
      if (end == start) continue;
      if (auto parsed = parseIndexLine(text.substr(start, end - start)))
        index.byId[parsed->first].push_back(std::move(parsed->second));
      else
        ++index.ignoredLines;
    }
    if (start < text.size()) ++index.ignoredLines;
  }
  return index;
}

// Whether `entry` records exactly the view's files, each on disk with its size and checksum.
bool filesVerified(const View& v, const IndexEntry& entry, const fs::path& dir) {
  if (entry.files.size() != v.outputs.size()) return false;
  for (size_t i = 0; i < v.outputs.size(); ++i) {
    const FileRecord& record = entry.files[i];
    if (record.file != v.outputs[i].file) return false;
    std::error_code ec;
    if (fs::file_size(dir / record.file, ec) != record.bytes || ec) return false;
    if (sha256OfFile(dir / record.file) != record.sha256) return false;
  }
  return true;
}

enum class Found { NotRecorded, Changed, Complete };
Found findComplete(const View& v, const Index& index, const fs::path& dir) {
  const auto it = index.byId.find(v.id);
  if (it == index.byId.end()) return Found::NotRecorded;
  for (auto entry = it->second.rbegin(); entry != it->second.rend(); ++entry)
    if (entry->digest == v.digest && filesVerified(v, *entry, dir)) return Found::Complete;
  return Found::Changed;
}

// The temporaries a killed run left of this shard's files ("FILE.tmp-PID-N", io.hpp). Other
// shards' are not touched: their runs may be writing them now.
void removeTemporaries(const fs::path& dir, std::span<const View> views) {
  std::unordered_set<std::string> files;
  for (const View& v : views)
    for (const ViewOutput& o : v.outputs) files.insert(o.file);
  for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    const size_t tmp = name.rfind(".tmp-");
    if (tmp != std::string::npos && files.count(name.substr(0, tmp))) fs::remove(e.path());
  }
}

// Appends whole lines to a shard's index. Each line goes out in one write() ending in its
// newline; a line a kill tore is ended first, so that it stays a line of its own, ignored.
class IndexAppender {
 public:
  explicit IndexAppender(fs::path path) : path_(std::move(path)) {}
  ~IndexAppender() {
    if (fd_ >= 0) ::close(fd_);
  }
  IndexAppender(const IndexAppender&) = delete;
  IndexAppender& operator=(const IndexAppender&) = delete;

  void append(const std::string& line) {
    if (fd_ < 0) open();
    writeAll(line + "\n");
  }

 private:
  void open() {
    fd_ = ::open(path_.c_str(), O_RDWR | O_APPEND | O_CREAT | O_CLOEXEC, 0666);
    if (fd_ < 0) fail("cannot open");
    struct stat st;
    char last = '\n';
    if (::fstat(fd_, &st) != 0 || (st.st_size > 0 && ::pread(fd_, &last, 1, st.st_size - 1) != 1)) fail("cannot read");
    if (last != '\n') writeAll("\n");
  }
  void writeAll(const std::string& text) {
    for (size_t done = 0; done < text.size();) {
      const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) fail("cannot write");
      done += size_t(n);
    }
  }
  [[noreturn]] void fail(const char* what) const {
    throw std::runtime_error(path_.string() + ": " + what + ": " + std::strerror(errno));
  }

  fs::path path_;
  int fd_ = -1;
};

std::string indexLine(const View& v, const std::vector<FileRecord>& files) {
  nlohmann::ordered_json line{{"id", v.id}, {"view_sha256", v.digest}, {"files", nlohmann::ordered_json::array()}};
  for (const FileRecord& f : files)
    line["files"].push_back({{"output", f.output}, {"file", f.file}, {"bytes", f.bytes}, {"sha256", f.sha256}});
  return line.dump();
}

// ---------------------------------------------------------------------------------------------
// Rendering: views grouped by scene (each loaded once) and by algorithm (one Renderer each).

// The scene being rendered and what is made for it once.
struct SceneInUse {
  std::string name;
  std::unique_ptr<hsr::Scene> scene;  // the Renderers point at it
  std::optional<std::vector<int32_t>> meshOfFace;  // instance ids, made when first asked for
  std::map<std::string, hsr::Renderer> renderers;  // by View::rendererKey

  void load(const View& first) {
    renderers.clear();  // before the scene they point at
    meshOfFace.reset();
    scene.reset();
    name = first.scene;
    try {
      scene = std::make_unique<hsr::Scene>(hsr::loadScene(first.scene));
    } catch (const hsr::InputError& e) {
      throw InputError(first.where + ": scene: " + manifestWording(e));
    }
  }
  hsr::Renderer& rendererFor(const View& v, const hsr::RenderOptions& options) {
    auto it = renderers.find(v.rendererKey());
    if (it == renderers.end()) it = renderers.emplace(v.rendererKey(), hsr::Renderer(*scene, options)).first;
    return it->second;
  }
  const std::vector<int32_t>& meshIndices() {
    if (!meshOfFace) meshOfFace = hsr::faceMeshIndices(*scene);
    return *meshOfFace;
  }
};

// The views in the order they are rendered: by scene, then by algorithm and parameters, in the
// order each first appears; else in manifest order.
std::vector<const View*> renderOrder(const std::vector<const View*>& views) {
  std::unordered_map<std::string, size_t> sceneRank, rendererRank;
  std::vector<std::tuple<size_t, size_t, size_t>> keyed;  // scene's rank, renderer's rank, position
  for (size_t i = 0; i < views.size(); ++i) {
    const size_t scene = sceneRank.emplace(views[i]->scene, sceneRank.size()).first->second;
    const size_t renderer = rendererRank.emplace(views[i]->rendererKey(), rendererRank.size()).first->second;
    keyed.emplace_back(scene, renderer, i);
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<const View*> order;
  for (const auto& [scene, renderer, i] : keyed) order.push_back(views[i]);
  return order;
}

void writeOutput(OutputKind kind, const std::string& path, const hsr::Frame& frame, const hsr::Camera& camera,
                 SceneInUse& s) {
  switch (kind) {
    case OutputKind::Depth: return hsr::writeDepth(frame, path);
    case OutputKind::FaceId: return hsr::writeFaceIds(frame, path);
    case OutputKind::InstanceId: return hsr::writeInstanceIds(frame, s.meshIndices(), path);
    case OutputKind::Barycentric: return hsr::writeBarycentrics(*s.scene, camera, frame, path);
    case OutputKind::Color: return hsr::writeColorPng(frame, path);
    case OutputKind::DepthImage: return hsr::writeDepthImage(frame, path);
  }
}

// Renders one view, writes its files (all or none) and returns their records, each file hashed
// as it lies on disk.
std::vector<FileRecord> renderView(const View& v, SceneInUse& s, int threads, const fs::path& dir,
                                   hsr::Frame& frame) {
  // 1. The camera: the view's, else the scene's, else a framing of the scene.
  const hsr::Bounds3 bounds = s.scene->bounds();
  const hsr::CameraSpec spec = v.camera ? *v.camera : s.scene->camera ? *s.scene->camera : hsr::frameBounds(bounds);
  const hsr::Camera camera = hsr::resolveCamera(spec, v.size->width, v.size->height, bounds, v.where);
  // 2. The frame, with only the buffers the outputs are written from.
  hsr::RenderOptions options;
  options.algorithm = v.algorithm;
  options.params = v.params;
  options.threads = threads;
  if (v.depthFormat) options.depthFormat = *v.depthFormat;
  options.outputs = hsr::FrameOutputs::DepthOnly;  // (depth is always resolved)
  for (const ViewOutput& o : v.outputs) options.outputs = options.outputs | o.type->needs;
  try {
    s.rendererFor(v, options).render(camera, options, frame);
  } catch (const hsr::InputError& e) {
    throw InputError(v.where + ": " + manifestWording(e));
  }
  // 3. The files: all renamed into place together.
  {
    hsr::OutputBatch batch;
    for (const ViewOutput& o : v.outputs) writeOutput(o.type->kind, (dir / o.file).string(), frame, camera, s);
    batch.commit();
  }
  // 4. Their records for the index.
  std::vector<FileRecord> records;
  for (const ViewOutput& o : v.outputs) {
    const fs::path path = dir / o.file;
    const std::optional<std::string> sha256 = sha256OfFile(path);
    if (!sha256) throw std::runtime_error(path.string() + ": cannot read back: " + std::strerror(errno));
    records.push_back({o.type->name, o.file, *sha256, uint64_t(fs::file_size(path))});
  }
  return records;
}

// ---------------------------------------------------------------------------------------------

struct Tally {
  size_t views = 0, complete = 0, rendered = 0, renderedAgain = 0;
};

int runBatch(const BatchFlags& f) {
  // 1. The flags and the whole manifest, checked before anything is written.
  const Shard shard = parseShard(f.shard);
  const std::vector<View> views = readManifest(f.manifest);
  const fs::path dir = f.out;
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw InputError(fmt::format("--out '{}': exists and is not a folder", f.out));
  fs::create_directories(dir);

  // 2. This shard's views; those an earlier run completed (files verified) are skipped.
  const std::span<const View> mine = viewsOf(views, shard);
  const Index index = readIndexes(dir);
  removeTemporaries(dir, mine);
  Tally tally;
  tally.views = mine.size();
  std::vector<const View*> todo;
  for (const View& v : mine) {
    const Found found = findComplete(v, index, dir);
    if (found == Found::Complete) {
      ++tally.complete;
      if (f.verbose) fmt::print("{}: complete already\n", v.id);
      continue;
    }
    tally.renderedAgain += found == Found::Changed;
    todo.push_back(&v);
  }

  // 3. The rest, scene by scene, each view indexed once its files are in place.
  IndexAppender appender(dir / shard.indexFile());
  SceneInUse scene;
  hsr::Frame frame;
  for (const View* v : renderOrder(todo)) {
    const auto start = std::chrono::steady_clock::now();
    if (!scene.scene || scene.name != v->scene) scene.load(*v);
    const std::vector<FileRecord> records = renderView(*v, scene, f.threads, dir, frame);
    appender.append(indexLine(*v, records));
    ++tally.rendered;
    if (f.verbose) {
      fmt::print("{}: rendered, {} files, {:.1f} ms\n", v->id, records.size(), millisecondsSince(start));
      std::fflush(stdout);  // a log a kill cuts short still shows what was done
    }
  }

  // 4. What was done.
  if (!f.quiet)
    fmt::print("shard {}/{} of {}: {} views, {} rendered{}, {} complete already; index {}{}\n", shard.index,
               shard.count, f.manifest, tally.views, tally.rendered,
               tally.renderedAgain ? fmt::format(" ({} again: a file missing or changed, or the view changed)",
                                                 tally.renderedAgain)
                                   : "",
               tally.complete, (dir / shard.indexFile()).string(),
               index.ignoredLines ? fmt::format(" ({} index lines ignored: torn or not index lines)",
                                                index.ignoredLines)
                                  : "");
  return 0;
}

}  // namespace

Runner setupBatch(CLI::App& cmd) {
  auto f = std::make_shared<BatchFlags>();
  cmd.add_option("manifest", f->manifest,
                 "Views, one JSON object per line: id, scene, camera, size, outputs, and optionally algorithm, "
                 "params, depth_format (docs/distributed.md)")
      ->type_name("MANIFEST.jsonl")
      ->required();
  cmd.add_option("--out", f->out, "Folder of the outputs (ID.OUTPUT.EXT) and the index files (made if missing)")
      ->type_name("DIR")
      ->required();
  cmd.add_option("--shard", f->shard,
                 "Render only shard I of N (0 <= I < N): the I-th of N contiguous blocks of the manifest's views")
      ->type_name("I/N");
  cmd.add_option("--threads", f->threads, "Worker threads per frame (0 = all cores)")
      ->type_name("N")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str();
  CLI::Option* verbose = cmd.add_flag("-v,--verbose", f->verbose, "A line per view: rendered, or complete already");
  cmd.add_flag("-q,--quiet", f->quiet, "Print nothing on success")->excludes(verbose);
  cmd.footer(
      "Each view's files are written atomically, then one line is appended to DIR/index-I-of-N.jsonl with\n"
      "their SHA-256. A run skips the views already complete (files present, checksums equal) and renders\n"
      "the rest, so a killed run is resumed by running it again.\n\n"
      "Examples:\n"
      "  hsr batch views.jsonl --out out\n"
      "  hsr batch views.jsonl --out out --shard $SLURM_ARRAY_TASK_ID/8 --threads $SLURM_CPUS_PER_TASK");
  return [f] { return runBatch(*f); };
}

}  // namespace hsr::cli
