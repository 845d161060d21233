#include "stages/geometry/io/frames.h"

#include <nlohmann/json.hpp>
#include <set>

#include "base/env.h"

namespace pb {

const Frame* FrameSet::find(std::string_view name) const {
  for (const Frame& frame : frames)
    if (frame.entry.name == name) return &frame;
  return nullptr;
}

namespace {

bool EndsWithPng(const std::string& name) {
  if (name.size() < 5) return false;
  std::string ext = name.substr(name.size() - 4);
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".png";
}

nlohmann::json Vec3(const std::array<double, 3>& v) { return {v[0], v[1], v[2]}; }

// Reads key `key` of `object` as three numbers into `out`; false if absent.
Expected<bool> ReadVec3(const nlohmann::json& object, const char* key, std::array<double, 3>& out,
                        const std::string& where) {
  if (!object.contains(key)) return false;
  const nlohmann::json& v = object[key];
  if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
    return Status::Invalid(where + ": \"" + key + "\" must be an array of 3 numbers");
  for (int i = 0; i < 3; ++i) out[i] = v[i].get<double>();
  return true;
}

}  // namespace

Status Validate(const FramesIndex& index) {
  if (index.width <= 0 || index.height <= 0)
    return Status::Invalid("frames: width and height must be positive, got " +
                           std::to_string(index.width) + "x" + std::to_string(index.height));
  std::set<std::string> names, files;
  for (size_t i = 0; i < index.frames.size(); ++i) {
    const FrameEntry& f = index.frames[i];
    const std::string where = "frames[" + std::to_string(i) + "]";
    if (f.name.empty()) return Status::Invalid(where + ": empty name");
    if (!names.insert(f.name).second) return Status::Invalid(where + ": duplicate name '" + f.name + "'");
    // The frame's image and its optional depth and samples files: plain
    // file names with their extension, each used once in the set.
    auto check_file = [&](const std::string& file, const std::string& kind, const char* extension,
                          bool extension_ok) -> Status {
      if (file.find('/') != std::string::npos || file.find('\\') != std::string::npos ||
          file == "." || file == ".." || file == kFramesIndexFile || !extension_ok)
        return Status::Invalid(where + " '" + f.name + "': " + kind + "file '" + file +
                               "' must be a plain file name ending in " + extension);
      if (!files.insert(file).second)
        return Status::Invalid(where + " '" + f.name + "': file '" + file + "' used twice");
      return Status::Ok();
    };
    PB_RETURN_IF_ERROR(check_file(f.file, "", ".png", !f.file.empty() && EndsWithPng(f.file)));
    const std::string& d = f.depth_file;
    if (!d.empty()) {
      PB_RETURN_IF_ERROR(check_file(
          d, "depth ", ".exr", d.size() > 4 && d.compare(d.size() - 4, 4, ".exr") == 0));
    }
    if (!f.samples_file.empty()) {
      PB_RETURN_IF_ERROR(
          check_file(f.samples_file, "samples ", ".png", EndsWithPng(f.samples_file)));
    }
  }
  return Status::Ok();
}

std::string FramesIndexToJson(const FramesIndex& index) {
  nlohmann::json frames = nlohmann::json::array();
  for (const FrameEntry& f : index.frames) {
    nlohmann::json entry = {{"name", f.name}, {"file", f.file}};
    if (f.viewpoint) {
      entry["eye"] = Vec3(f.viewpoint->eye);
      entry["target"] = Vec3(f.viewpoint->target);
      if (f.viewpoint->up) entry["up"] = Vec3(*f.viewpoint->up);
      if (f.viewpoint->fov_deg) entry["fov_deg"] = *f.viewpoint->fov_deg;
    }
    if (!f.depth_file.empty()) entry["depth"] = f.depth_file;
    if (!f.samples_file.empty()) entry["samples"] = f.samples_file;
    frames.push_back(std::move(entry));
  }
  nlohmann::json document = nlohmann::json::object();
  document["format"] = kFramesFormat;
  document["version"] = kFramesVersion;
  document["width"] = index.width;
  document["height"] = index.height;
  document["frames"] = std::move(frames);
  return document.dump(1) + "\n";
}

Expected<FramesIndex> FramesIndexFromJson(std::string_view json_text, const std::string& source) {
  const nlohmann::json document =
      nlohmann::json::parse(json_text.begin(), json_text.end(), nullptr, /*allow_exceptions=*/false);
  if (document.is_discarded()) return Status::Corrupt(source + ": not valid JSON");
  if (!document.is_object() || document.value("format", nlohmann::json()) != kFramesFormat)
    return Status::Corrupt(source + ": not a frames index (expected \"format\": \"" +
                           std::string(kFramesFormat) + "\")");
  const nlohmann::json version = document.value("version", nlohmann::json());
  if (!version.is_number_integer())
    return Status::Corrupt(source + ": \"version\" must be an integer");
  if (version.get<int64_t>() != kFramesVersion)
    return Status::Unsupported(source + ": frames format version " + version.dump() +
                               "; this build reads version " + std::to_string(kFramesVersion));
  FramesIndex index;
  for (const auto& [key, out] : {std::pair{"width", &index.width}, std::pair{"height", &index.height}}) {
    const nlohmann::json v = document.value(key, nlohmann::json());
    if (!v.is_number_integer() || v.get<int64_t>() <= 0 || v.get<int64_t>() > 1 << 20)
      return Status::Invalid(source + ": \"" + key + "\" must be a positive integer");
    *out = int(v.get<int64_t>());
  }
  const nlohmann::json frames = document.value("frames", nlohmann::json());
  if (!frames.is_array()) return Status::Invalid(source + ": \"frames\" must be an array");
  for (size_t i = 0; i < frames.size(); ++i) {
    const nlohmann::json& f = frames[i];
    const std::string where = source + ": frames[" + std::to_string(i) + "]";
    if (!f.is_object() || !f.contains("name") || !f["name"].is_string() || !f.contains("file") ||
        !f["file"].is_string())
      return Status::Invalid(where + ": expected an object with string \"name\" and \"file\"");
    FrameEntry entry{f["name"].get<std::string>(), f["file"].get<std::string>(), std::nullopt};
    FrameViewpoint view;
    PB_ASSIGN_OR_RETURN(const bool has_eye, ReadVec3(f, "eye", view.eye, where));
    PB_ASSIGN_OR_RETURN(const bool has_target, ReadVec3(f, "target", view.target, where));
    std::array<double, 3> up{};
    PB_ASSIGN_OR_RETURN(const bool has_up, ReadVec3(f, "up", up, where));
    if (has_up) view.up = up;
    if (f.contains("fov_deg")) {
      if (!f["fov_deg"].is_number()) return Status::Invalid(where + ": \"fov_deg\" must be a number");
      view.fov_deg = f["fov_deg"].get<double>();
    }
    if (has_eye != has_target || ((has_up || view.fov_deg) && !has_eye))
      return Status::Invalid(where + ": a viewpoint needs both \"eye\" and \"target\"");
    if (has_eye) entry.viewpoint = view;
    if (f.contains("depth")) {
      if (!f["depth"].is_string()) return Status::Invalid(where + ": \"depth\" must be a file name");
      entry.depth_file = f["depth"].get<std::string>();
    }
    if (f.contains("samples")) {
      if (!f["samples"].is_string()) return Status::Invalid(where + ": \"samples\" must be a file name");
      entry.samples_file = f["samples"].get<std::string>();
    }
    index.frames.push_back(std::move(entry));
  }
  PB_RETURN_IF_ERROR(Validate(index).WithContext(source));
  return index;
}

Expected<FrameSet> ReadFrames(const std::string& index_path, const FramesFilePath& path_of) {
  Expected<std::string> text = Env::Default()->ReadFile(index_path);
  if (!text.ok()) return text.status();
  PB_ASSIGN_OR_RETURN(FramesIndex index, FramesIndexFromJson(*text, index_path));
  const size_t slash = index_path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : index_path.substr(0, slash);
  FrameSet set;
  set.width = index.width;
  set.height = index.height;
  for (FrameEntry& entry : index.frames) {
    const std::string path = path_of ? path_of(entry.file) : JoinPath(dir, entry.file);
    const std::string what = index_path + ": frame '" + entry.name + "'";
    if (path.empty() || !Env::Default()->Exists(path))
      return Status::NotFound(what + ": missing image file '" + entry.file + "'");
    Expected<Image> image = ReadPng(path);
    if (!image.ok()) return image.status().WithContext(what);
    if (image->type != Image::PixelType::kU8 || (image->channels != 3 && image->channels != 4))
      return Status::Invalid(what + ": " + entry.file + " must be an 8-bit RGB or RGBA PNG");
    if (image->width != index.width || image->height != index.height)
      return Status::Invalid(what + ": " + entry.file + " is " + std::to_string(image->width) + "x" +
                             std::to_string(image->height) + ", the set is " +
                             std::to_string(index.width) + "x" + std::to_string(index.height));
    // A depth (one-channel float EXR) or samples (8-bit gray PNG) image of
    // the frame's size.
    auto read_side = [&](const std::string& file, const char* kind, bool exr) -> Expected<Image> {
      const std::string side_path = path_of ? path_of(file) : JoinPath(dir, file);
      if (side_path.empty() || !Env::Default()->Exists(side_path))
        return Status::NotFound(what + ": missing " + kind + " file '" + file + "'");
      Expected<Image> read = exr ? ReadExr(side_path) : ReadPng(side_path);
      if (!read.ok()) return read.status().WithContext(what);
      if (read->type != (exr ? Image::PixelType::kF32 : Image::PixelType::kU8) ||
          read->channels != 1 || read->width != index.width || read->height != index.height)
        return Status::Invalid(what + ": " + file + " must be " +
                               (exr ? "a one-channel float " : "an 8-bit gray ") +
                               std::to_string(index.width) + "x" + std::to_string(index.height) +
                               (exr ? " EXR" : " PNG"));
      return read;
    };
    Image depth, samples;
    if (!entry.depth_file.empty()) {
      PB_ASSIGN_OR_RETURN(depth, read_side(entry.depth_file, "depth", true));
    }
    if (!entry.samples_file.empty()) {
      PB_ASSIGN_OR_RETURN(samples, read_side(entry.samples_file, "samples", false));
    }
    set.frames.push_back(
        Frame{std::move(entry), std::move(image).value(), std::move(depth), std::move(samples)});
  }
  return set;
}

Status WriteFrames(const FrameSet& frames, const FramesFilePath& path_of, Env* env) {
  FramesIndex index;
  index.width = frames.width;
  index.height = frames.height;
  for (const Frame& f : frames.frames) index.frames.push_back(f.entry);
  PB_RETURN_IF_ERROR(Validate(index).WithContext("writing frames"));
  std::vector<std::vector<uint8_t>> pngs;
  std::vector<std::string> depths, depth_paths;  // depth maps (EXR), when the frames have them
  std::vector<std::vector<uint8_t>> masks;         // sample masks (PNG), when the frames have them
  std::vector<std::string> mask_paths;
  for (const Frame& f : frames.frames) {
    const Image& image = f.image;
    if (image.type != Image::PixelType::kU8 || (image.channels != 3 && image.channels != 4) ||
        image.width != frames.width || image.height != frames.height)
      return Status::Invalid("writing frames: frame '" + f.entry.name + "' must be an 8-bit RGB(A) " +
                             std::to_string(frames.width) + "x" + std::to_string(frames.height) +
                             " image");
    PB_ASSIGN_OR_RETURN(pngs.emplace_back(), EncodePng(image));
    if (!f.entry.depth_file.empty()) {
      const Image& depth = f.depth;
      if (depth.type != Image::PixelType::kF32 || depth.channels != 1 || depth.width != frames.width ||
          depth.height != frames.height)
        return Status::Invalid("writing frames: frame '" + f.entry.name + "' names a depth file but has no " +
                               std::to_string(frames.width) + "x" + std::to_string(frames.height) +
                               " one-channel float depth map");
      PB_ASSIGN_OR_RETURN(depths.emplace_back(), EncodeExr(depth, path_of(f.entry.depth_file)));
      depth_paths.push_back(path_of(f.entry.depth_file));
    }
    if (!f.entry.samples_file.empty()) {
      const Image& samples = f.samples;
      if (samples.type != Image::PixelType::kU8 || samples.channels != 1 || samples.width != frames.width ||
          samples.height != frames.height)
        return Status::Invalid("writing frames: frame '" + f.entry.name + "' names a samples file but has no " +
                               std::to_string(frames.width) + "x" + std::to_string(frames.height) +
                               " one-channel 8-bit sample mask");
      PB_ASSIGN_OR_RETURN(masks.emplace_back(), EncodePng(samples));
      mask_paths.push_back(path_of(f.entry.samples_file));
    }
  }
  const std::string index_json = FramesIndexToJson(index);
  std::vector<FileContents> files;
  for (size_t i = 0; i < pngs.size(); ++i) {
    files.push_back({path_of(frames.frames[i].entry.file),
                     std::string_view(reinterpret_cast<const char*>(pngs[i].data()), pngs[i].size())});
  }
  for (size_t i = 0; i < depths.size(); ++i) files.push_back({depth_paths[i], depths[i]});
  for (size_t i = 0; i < masks.size(); ++i)
    files.push_back({mask_paths[i], std::string_view(reinterpret_cast<const char*>(masks[i].data()), masks[i].size())});
  files.push_back({path_of(kFramesIndexFile), index_json});
  return WriteFilesAtomic(env, files);
}

Status WriteFrames(const std::string& dir, const FrameSet& frames, Env* env) {
  return WriteFrames(frames, [&dir](const std::string& file) { return JoinPath(dir, file); }, env);
}

}  // namespace pb
