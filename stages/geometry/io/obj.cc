// Wavefront OBJ/MTL writer and reader (see obj.h). Formats after Wavefront's
// "Object Files (.obj)" and "MTL Material Format" (Advanced Visualizer 3.0);
// `norm` is the PBR extension's normal map key; colors on `v` lines the
// extension MeshLab and Blender read.
#include "stages/geometry/io/obj.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>

#include "stages/geometry/core/tangents.h"
#include "stages/geometry/core/text_parse.h"

namespace pb {
namespace {

const uint8_t kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};

bool IsPng(const std::vector<uint8_t>& bytes) {
  return bytes.size() >= 8 && std::equal(kPngSignature, kPngSignature + 8, bytes.begin());
}

// Shortest text that reads back to the same value.
template <typename T>
void AppendNumber(std::string* out, T value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out->append(buffer, result.ptr);
}

void AppendIndex(std::string* out, uint64_t value) {
  char buffer[24];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out->append(buffer, result.ptr);
}

std::string ObjText(const Mesh& mesh, const std::vector<float>& normals, const ObjWriteOptions& options,
                    const std::string& mtl_name) {
  const size_t n = mesh.vertex_count();
  const bool colors = mesh.has_colors() && options.vertex_colors;
  std::string text;
  text.reserve(n * (colors ? 110 : 80) + mesh.indices.size() * 24 + 256);
  text += "# pointbake obj " + std::to_string(kObjVersion) + "\n";
  text += "# origin " + FormatDouble(mesh.origin[0]) + " " + FormatDouble(mesh.origin[1]) + " " +
          FormatDouble(mesh.origin[2]) + "\n";
  text += options.absolute_coordinates ? "# coordinates absolute\n" : "# coordinates relative\n";
  text += "mtllib " + mtl_name + "\no " + options.name + "\n";
  for (size_t v = 0; v < n; ++v) {
    text += 'v';
    for (int k = 0; k < 3; ++k) {
      text += ' ';
      if (options.absolute_coordinates) {
        AppendNumber(&text, mesh.origin[k] + double(mesh.positions[3 * v + k]));
      } else {
        AppendNumber(&text, mesh.positions[3 * v + k]);
      }
    }
    if (colors) {
      for (int k = 0; k < 3; ++k) {
        text += ' ';
        AppendNumber(&text, mesh.colors[3 * v + k] / 255.0f);
      }
    }
    text += '\n';
  }
  if (mesh.has_uvs()) {
    for (size_t v = 0; v < n; ++v) {
      text += "vt ";
      AppendNumber(&text, mesh.uvs[2 * v]);
      text += ' ';
      AppendNumber(&text, mesh.uvs[2 * v + 1]);
      text += '\n';
    }
  }
  for (size_t v = 0; v < n; ++v) {
    text += "vn";
    for (int k = 0; k < 3; ++k) {
      text += ' ';
      AppendNumber(&text, normals[3 * v + k]);
    }
    text += '\n';
  }
  text += "usemtl " + options.name + "\n";
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    text += 'f';
    for (int c = 0; c < 3; ++c) {
      const uint64_t index = uint64_t(mesh.indices[3 * f + c]) + 1;
      text += ' ';
      AppendIndex(&text, index);
      text += '/';
      if (mesh.has_uvs()) AppendIndex(&text, index);
      text += '/';
      AppendIndex(&text, index);
    }
    text += '\n';
  }
  return text;
}

std::string MtlText(const ObjWriteOptions& options) {
  std::string text = "# pointbake mtl " + std::to_string(kObjVersion) + "\n";
  text += "newmtl " + options.name + "\n";
  text += "Ka 0 0 0\nKd 1 1 1\nKs 0 0 0\nd 1\nillum 1\n";
  if (!options.base_color_png.empty()) text += "map_Kd color.png\n";
  if (!options.normal_png.empty()) text += "map_Bump normal.png\nnorm normal.png\n";
  return text;
}

}  // namespace

Status WriteObj(const std::string& obj_path, const Mesh& mesh, const ObjWriteOptions& options,
                ObjWriteReport* report, Env* env) {
  ObjWriteReport local;
  ObjWriteReport& out = report ? *report : local;
  out = ObjWriteReport{};
  const std::string context = "writing " + obj_path;
  PB_RETURN_IF_ERROR(Validate(mesh).WithContext(context));
  if (mesh.face_count() == 0) return Status::Invalid(context + ": the mesh has no triangles");
  const bool has_color = !options.base_color_png.empty(), has_normal = !options.normal_png.empty();
  if ((has_color || has_normal) && !mesh.has_uvs()) {
    return Status::Invalid(context + ": textures need uvs, and the mesh has none (unwrap it first)");
  }
  if ((has_color && !IsPng(options.base_color_png)) || (has_normal && !IsPng(options.normal_png))) {
    return Status::Invalid(context + ": a texture is not a PNG");
  }
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    if (!std::isfinite(mesh.positions[i])) {
      return Status::Invalid(context + ": vertex " + std::to_string(i / 3) + " has a non-finite coordinate");
    }
  }
  out.computed_normals = !mesh.has_normals();
  std::vector<float> normals = out.computed_normals ? ComputeVertexNormals(mesh) : mesh.normals;
  if (!out.computed_normals) {
    const std::vector<float> fallback = ComputeVertexNormals(mesh);
    for (size_t v = 0; v < mesh.vertex_count(); ++v) {
      float* nv = &normals[3 * v];
      const double length = std::sqrt(double(nv[0]) * nv[0] + double(nv[1]) * nv[1] + double(nv[2]) * nv[2]);
      for (int k = 0; k < 3; ++k) {
        nv[k] = length > 0 && std::isfinite(length) ? float(nv[k] / length) : fallback[3 * v + k];
      }
    }
  }

  const std::filesystem::path obj(obj_path);
  const std::string mtl_name = obj.stem().string() + ".mtl";
  auto bytes_of = [](const std::vector<uint8_t>& v) {
    return std::string_view(reinterpret_cast<const char*>(v.data()), v.size());
  };
  // The .obj is published last: it is the file a viewer opens.
  const std::string obj_text = ObjText(mesh, normals, options, mtl_name);
  const std::string mtl_text = MtlText(options);
  std::vector<FileContents> files;
  if (has_color) files.push_back({(obj.parent_path() / "color.png").string(), bytes_of(options.base_color_png)});
  if (has_normal) files.push_back({(obj.parent_path() / "normal.png").string(), bytes_of(options.normal_png)});
  files.push_back({(obj.parent_path() / mtl_name).string(), mtl_text});
  files.push_back({obj.string(), obj_text});

  PB_RETURN_IF_ERROR(WriteFilesAtomic(env, files));
  out.files.push_back(obj.string());
  out.files.push_back(files[files.size() - 2].path);
  for (size_t i = 0; i + 2 < files.size(); ++i) out.files.push_back(files[i].path);
  for (const FileContents& file : files) out.bytes += file.bytes.size();
  return Status::Ok();
}

// ---------------------------------------------------------------------------
// Reading.

namespace {

Expected<std::string> ReadWholeFile(const std::string& path) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) return Status::NotFound(path + ": no such file");
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Errno(path, "open");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) return Status::Errno(path, "read");
  return text.str();
}

struct Corner {
  int64_t v = 0, t = -1, n = -1;  // 0-based; -1 absent
  bool operator<(const Corner& o) const { return std::tie(v, t, n) < std::tie(o.v, o.t, o.n); }
};

struct MtlMaps {
  std::string color, normal;  // file names as written in the MTL
};

Expected<MtlMaps> ReadMtl(const std::string& path, const std::string& material) {
  PB_ASSIGN_OR_RETURN(std::string text, ReadWholeFile(path));
  MtlMaps maps;
  std::string current;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    const std::vector<std::string_view> words = SplitWords(line);
    if (words.size() < 2 || words[0][0] == '#') continue;
    if (words[0] == "newmtl") current = std::string(words[1]);
    if (!material.empty() && current != material) continue;
    // The file name is the last word; options (-bm 1.0 ...) come before it.
    const std::string file(words.back());
    if (words[0] == "map_Kd" && maps.color.empty()) maps.color = file;
    if ((words[0] == "norm" || words[0] == "map_Bump" || words[0] == "map_bump" || words[0] == "bump") &&
        maps.normal.empty()) {
      maps.normal = file;
    }
  }
  return maps;
}

Expected<std::vector<uint8_t>> ReadBytes(const std::string& path) {
  PB_ASSIGN_OR_RETURN(std::string text, ReadWholeFile(path));
  return std::vector<uint8_t>(text.begin(), text.end());
}

}  // namespace

Expected<ObjModel> ReadObj(const std::string& obj_path) {
  PB_ASSIGN_OR_RETURN(std::string text, ReadWholeFile(obj_path));
  std::vector<double> positions;
  std::vector<float> colors, uvs, normals;
  std::vector<Corner> corners;
  std::optional<std::array<double, 3>> origin;
  bool relative = false;  // "# coordinates relative": v lines are relative to the origin
  std::string mtllib;
  ObjModel model;
  size_t line_number = 0, start = 0;
  auto error = [&](const std::string& what) {
    return Status::Corrupt(obj_path + ":" + std::to_string(line_number) + ": " + what);
  };
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string_view line(text.data() + start, end - start);
    start = end + 1;
    ++line_number;
    // Most lines have a few words: split without allocating, and fall back
    // to a vector for long polygons.
    std::string_view fixed_words[16];
    std::vector<std::string_view> many_words;
    const std::string_view* words = fixed_words;
    size_t count = SplitWords(line, fixed_words, 16);
    if (count > 16) {
      many_words = SplitWords(line);
      words = many_words.data();
      count = many_words.size();
    }
    if (count == 0) continue;
    const std::string_view key = words[0];
    auto numbers = [&](size_t first, size_t how_many, double* out) {
      for (size_t i = 0; i < how_many; ++i) {
        if (first + i >= count || !ParseDouble(words[first + i], &out[i])) return false;
      }
      return true;
    };
    double values[6];
    if (key == "#" && count == 5 && words[1] == "origin") {
      if (!numbers(2, 3, values)) return error("malformed origin comment");
      origin = std::array<double, 3>{values[0], values[1], values[2]};
    } else if (key == "#" && count == 3 && words[1] == "coordinates") {
      relative = words[2] == "relative";
    } else if (key == "v") {
      if (!numbers(1, 3, values)) return error("expected 'v x y z'");
      positions.insert(positions.end(), values, values + 3);
      if (count >= 7 && numbers(4, 3, values + 3)) {
        colors.resize(positions.size() - 3, 0.0f);
        colors.insert(colors.end(), {float(values[3]), float(values[4]), float(values[5])});
      }
    } else if (key == "vt") {
      if (!numbers(1, 2, values)) return error("expected 'vt u v'");
      uvs.insert(uvs.end(), {float(values[0]), float(values[1])});
    } else if (key == "vn") {
      if (!numbers(1, 3, values)) return error("expected 'vn x y z'");
      normals.insert(normals.end(), {float(values[0]), float(values[1]), float(values[2])});
    } else if (key == "f") {
      if (count < 4) return error("a face needs at least 3 corners");
      std::vector<Corner> polygon;
      for (size_t i = 1; i < count; ++i) {
        Corner corner;
        int64_t* fields[3] = {&corner.v, &corner.t, &corner.n};
        const size_t sizes[3] = {positions.size() / 3, uvs.size() / 2, normals.size() / 3};
        std::string_view rest = words[i];
        for (int f = 0; f < 3 && !rest.empty(); ++f) {
          const size_t slash = rest.find('/');
          const std::string_view field = rest.substr(0, slash);
          rest = slash == std::string_view::npos ? std::string_view() : rest.substr(slash + 1);
          if (field.empty()) {
            if (f == 0) return error("a face corner without a vertex index");
            continue;
          }
          int64_t index = 0;
          const auto parsed = std::from_chars(field.data(), field.data() + field.size(), index);
          if (parsed.ec != std::errc() || parsed.ptr != field.data() + field.size() || index == 0) {
            return error("malformed face corner '" + std::string(words[i]) + "'");
          }
          index = index < 0 ? int64_t(sizes[f]) + index : index - 1;
          if (index < 0 || index >= int64_t(sizes[f])) {
            return error("face index " + std::string(field) + " out of range (" +
                         std::to_string(sizes[f]) + (f == 0 ? " vertices)" : f == 1 ? " uvs)" : " normals)"));
          }
          *fields[f] = index;
        }
        polygon.push_back(corner);
      }
      for (size_t i = 1; i + 1 < polygon.size(); ++i) {
        corners.insert(corners.end(), {polygon[0], polygon[i], polygon[i + 1]});
      }
    } else if (key == "mtllib" && count >= 2 && mtllib.empty()) {
      mtllib = std::string(words[1]);
    } else if (key == "usemtl" && count >= 2 && model.material.empty()) {
      model.material = std::string(words[1]);
    }
  }
  if (!colors.empty()) colors.resize(positions.size(), 0.0f);

  Mesh& mesh = model.mesh;
  const size_t vertex_count = positions.size() / 3;
  if (origin) {
    mesh.origin = *origin;
  } else if (vertex_count > 0 && !relative) {
    for (int k = 0; k < 3; ++k) {
      double lo = positions[k], hi = positions[k];
      for (size_t v = 0; v < vertex_count; ++v) {
        lo = std::min(lo, positions[3 * v + k]);
        hi = std::max(hi, positions[3 * v + k]);
      }
      mesh.origin[k] = std::round(0.5 * (lo + hi));
    }
  }
  const bool any_uv = std::any_of(corners.begin(), corners.end(), [](const Corner& c) { return c.t >= 0; });
  const bool any_normal = std::any_of(corners.begin(), corners.end(), [](const Corner& c) { return c.n >= 0; });
  // Corners that all name the same index for v, vt and vn keep the file's
  // vertex order (what pointbake writes); otherwise one vertex per triple.
  const bool aligned = std::all_of(corners.begin(), corners.end(), [&](const Corner& c) {
    return (c.t == c.v || !any_uv) && (c.n == c.v || !any_normal) && (c.t >= 0) == any_uv &&
           (c.n >= 0) == any_normal;
  });
  std::vector<Corner> vertices;
  if (aligned) {
    for (size_t v = 0; v < vertex_count; ++v) {
      vertices.push_back({int64_t(v), any_uv ? int64_t(v) : -1, any_normal ? int64_t(v) : -1});
    }
    for (const Corner& c : corners) mesh.indices.push_back(static_cast<uint32_t>(c.v));
  } else {
    std::map<Corner, uint32_t> index_of;
    for (const Corner& c : corners) {
      auto [it, inserted] = index_of.emplace(c, static_cast<uint32_t>(vertices.size()));
      if (inserted) vertices.push_back(c);
      mesh.indices.push_back(it->second);
    }
  }
  const bool keep_uvs = any_uv && std::all_of(vertices.begin(), vertices.end(), [](const Corner& c) { return c.t >= 0; });
  const bool keep_normals = any_normal && std::all_of(vertices.begin(), vertices.end(), [](const Corner& c) { return c.n >= 0; });
  for (const Corner& c : vertices) {
    for (int k = 0; k < 3; ++k) {
      const double p = positions[3 * c.v + k];
      mesh.positions.push_back(static_cast<float>(relative ? p : p - mesh.origin[k]));
    }
    if (!colors.empty()) {
      for (int k = 0; k < 3; ++k) {
        mesh.colors.push_back(static_cast<uint8_t>(std::lround(std::clamp(colors[3 * c.v + k], 0.0f, 1.0f) * 255.0f)));
      }
    }
    if (keep_uvs) mesh.uvs.insert(mesh.uvs.end(), {uvs[2 * c.t], uvs[2 * c.t + 1]});
    if (keep_normals) {
      mesh.normals.insert(mesh.normals.end(), {normals[3 * c.n], normals[3 * c.n + 1], normals[3 * c.n + 2]});
    }
  }

  if (!mtllib.empty()) {
    const std::filesystem::path dir = std::filesystem::path(obj_path).parent_path();
    auto maps = ReadMtl((dir / mtllib).string(), model.material);
    if (!maps.ok()) return maps.status().WithContext("reading " + obj_path);
    if (!maps->color.empty()) {
      PB_ASSIGN_OR_RETURN(model.base_color_png, ReadBytes((dir / maps->color).string()));
    }
    if (!maps->normal.empty()) {
      PB_ASSIGN_OR_RETURN(model.normal_png, ReadBytes((dir / maps->normal).string()));
    }
  }
  return model;
}

}  // namespace pb
