#include "cli/scene_command.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "base/env.h"
#include "base/units.h"
#include "cli/command_args.h"
#include "engine/workflow.h"
#include "stages/geometry/io/scan_read.h"
#include "stages/geometry/points/enclosure.h"
#include "stages/geometry/points/lost_station.h"
#include "stages/geometry/points/scene_survey.h"

namespace pb {
namespace {

namespace fs = std::filesystem;

constexpr const char* kDescription =
    "Write a scene file for a scan: its units, median spacing, the meshing and texture\n"
    "parameters of the shipped workflows in the shipped scenes' proportions, and\n"
    "viewpoints (from its scanner stations; without stations, from inside the space\n"
    "it encloses, a room's, or else face-on to it), each\n"
    "with a comment saying where it came from. Then:\n"
    "  pointbake run configs/workflows/point_transfer.yaml --scene FILE --until scan_render\n"
    "draws the scan from those viewpoints (out/point_transfer/scan_frames/) to check them;\n"
    "without --until, the workflow builds and evaluates its model.";

std::string Number(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

// A position in the scene's units, to a micrometre (2.9e-16 prints as 0).
std::string Vector(const std::array<double, 3>& v, double unit_m) {
  std::string out = "[";
  for (int k = 0; k < 3; ++k) {
    const double micrometres = std::round(v[k] * 1e6);
    out += (k ? ", " : "") + Number(micrometres == 0 ? 0.0 : micrometres / 1e6 / unit_m);
  }
  return out + "]";
}

// "4.7 mm", "1.25 m": a length for a comment.
std::string Length(double meters) {
  char buf[64];
  if (meters < 1.0)
    std::snprintf(buf, sizeof buf, "%.3g mm", meters * 1000);
  else
    std::snprintf(buf, sizeof buf, "%.3g m", meters);
  return buf;
}

// `text` as comment lines of at most `width` characters, each starting with
// `prefix` except the first (which continues a line already begun), words kept
// whole.
std::string WrapComment(const std::string& text, const std::string& prefix, size_t width) {
  std::string out, line;
  size_t begun = prefix.size() + 30;  // the first line continues one
  for (size_t start = 0; start < text.size();) {
    size_t end = text.find(' ', start);
    if (end == std::string::npos) end = text.size();
    const std::string word = text.substr(start, end - start);
    if (!line.empty() && begun + line.size() + 1 + word.size() > width) {
      out += line + "\n" + prefix;
      line.clear();
      begun = prefix.size();
    }
    line += (line.empty() ? "" : " ") + word;
    start = end + 1;
  }
  return out + line + "\n";
}

// A YAML double-quoted scalar: file names may hold quotes or backslashes.
std::string Quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string WithThousands(uint64_t v) {
  std::string digits = std::to_string(v), out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

// Parses "x,y,z" into `out`.
bool ParseVector(const std::string& text, std::array<double, 3>* out) {
  double v[3];
  char tail;
  if (std::sscanf(text.c_str(), "%lf,%lf,%lf%c", &v[0], &v[1], &v[2], &tail) != 3) return false;
  for (int k = 0; k < 3; ++k) {
    if (!std::isfinite(v[k])) return false;
    (*out)[k] = v[k];
  }
  return true;
}

std::string SceneYaml(const std::string& name, const std::string& scan_in_file,
                      const std::string& scan_path, const std::string& units, double unit_m,
                      const ScanReadResult& read, const SceneSurvey& survey,
                      const std::string& station_text, const std::string& station_found) {
  const std::array<double, 3> extent = survey.robust_bounds.extent_m();
  std::string y;
  y += "# Written by `pointbake scene` from " + scan_path + " (" + read.format + "):\n";
  y += "# " + WithThousands(survey.points) + " points";
  if (read.no_return_points > 0)
    y += " (and " + WithThousands(read.no_return_points) + " grid cells without a return)";
  if (read.dropped_points > 0)
    y += " (" + WithThousands(read.dropped_points) + " with NaN or infinite coordinates, dropped)";
  y += ", " + std::to_string(survey.stations) + " scanner station" + (survey.stations == 1 ? "" : "s") +
       (station_found.empty() ? "" : " (not in the file: found in the points)") + ", median spacing " +
       Length(survey.spacing_m) + ",\n";
  y += "# robust extent " + Length(extent[0]) + " x " + Length(extent[1]) + " x " +
       Length(extent[2]) + " (1st to 99th percentile per axis).\n";
  const EnclosureOptions enclosure;  // the survey's and points.normals' figures
  if (survey.enclosed_volume_m3 > 0 && !survey.enclosure_open)
    y += "# The points enclose " + Number(std::round(survey.enclosed_volume_m3)) + " m3 of free space (" +
         Number(enclosure.gap_m) +
         " m or more from them): an interior,\n"
         "# viewed from inside; points.normals (interior: auto) faces its normals in.\n";
  if (survey.enclosure_open)
    y += "# The points nearly enclose " + Number(std::round(survey.enclosed_volume_m3)) + " m3 of free space (" +
         Number(enclosure.open_gap_m) + " m or more from them; from it at\n# least " +
         Number(100 * enclosure.min_surrounded) +
         " % of the lines of sight meet the scan): an interior open on a side, or\n"
         "# small, viewed from inside; points.normals (interior: auto) faces its normals in.\n";
  if (survey.stations == 0 && !(survey.enclosed_volume_m3 > 0))
    y += "# No scanner station: nothing says which side of an open surface was scanned. If\n"
         "# this is one scan exported without its position, give --station x,y,z (where the\n"
         "# scanner stood); render.frames warns when the views see faces from behind.\n";
  y += "# The parameters follow the shipped scenes' proportions and the viewpoints are a\n";
  y += "# guess (stages/geometry/points/scene_survey.h): check them by drawing the scan,\n";
  y += "#   pointbake run configs/workflows/point_transfer.yaml --scene THIS_FILE --until "
       "scan_render\n";
  y += "# and edit what you know better (docs/real-scans.md, \"Your own scan\").\n";
  y += "name: " + name + "\n";
  y += "description: " +
       Quoted(name + ": " + WithThousands(survey.points) + " points read from " +
              fs::path(scan_path).filename().string()) +
       "\n";
  y += "units: " + units + "\n";
  y += "spacing_m: " + Number(survey.spacing_m) + "  # median nearest-neighbour distance, meters\n";
  y += "truth: false  # a real scan: the workflows are compared with the scan itself\n";
  y += "source:\n";
  y += "  uses: io.read_points\n";
  y += "  with: { path: " + Quoted(scan_in_file) +
       (station_text.empty() ? std::string() : ", station: [" + station_text + "]") + " }\n";
  if (!station_found.empty())
    y += "  # station: not in the file. Where the scanner stood, as pointbake scene found it in the\n"
         "  # points (stages/geometry/points/lost_station.h; file coordinates and units). Check it,\n"
         "  # edit it if you know better. Its figures: " +
         WrapComment(station_found + ".", "  # ", 88);
  else if (!station_text.empty())
    y += "  # station: where the scanner stood, as --station declared it (file coordinates and units)\n";
  y += "viewpoints:  # in " + units + ", like the scan\n";
  for (const SurveyViewpoint& view : survey.viewpoints) {
    y += "  # " + view.why + "\n";
    y += "  - { name: " + view.name + ", eye: " + Vector(view.eye, unit_m) +
         ", target: " + Vector(view.target, unit_m) + ", up: " + Vector(view.up, 1.0) +
         ", fov_deg: " + Number(view.fov_deg) + " }\n";
  }
  y += "params:\n";
  y += "  depth_high: " + std::to_string(survey.depth_high) +
       "  # screened Poisson depth of the HPM: cells about a spacing over the longest side\n";
  y += "  faces_high: " + std::to_string(survey.faces_high) + "  # one face per 2.5 points, in [" +
       std::to_string(kMinFacesHigh) + ", " + std::to_string(kMaxFacesHigh) + "]\n";
  y += "  depth_low: " + std::to_string(survey.depth_low) +
       "  # depth_high - 1, or - 2 from depth 10; at least 7\n";
  y += "  faces_low: " + std::to_string(survey.faces_low) + "  # a tenth of faces_high, at most " +
       std::to_string(kMaxFacesLow) + " (a headset's 60 FPS budget)\n";
  y += "  texture: " + std::to_string(survey.texture) + "  # about 256 texels per low face\n";
  y += "  frame_size: " + std::to_string(survey.frame_size) +
       "  # pixels of the evaluation frames\n";
  return y;
}

int RunScene(const std::vector<std::string>& args) {
  CLI::App app{kDescription, "pointbake scene"};
  std::string scan_path, out_path, units = "m", up_text = "0,0,1", name, format = "auto", station_text;
  bool force = false, no_find_station = false;
  app.add_option("SCAN", scan_path, "The scan file (PLY, PCD, XYZ/TXT/CSV/PTS, PTX, E57, LAS, LAZ)")
      ->required();
  app.add_option("-o,--out", out_path,
                 "Write the scene here (else to stdout, with the scan's absolute path)");
  std::vector<std::string> unit_names;
  for (const auto& [unit, meters] : kLengthUnits) unit_names.emplace_back(unit);
  app.add_option("--units", units, "The scan's length unit")
      ->check(CLI::IsMember(unit_names))
      ->capture_default_str();
  app.add_option("--up", up_text, "The scan's vertical direction, x,y,z in its frame")
      ->capture_default_str();
  app.add_option("--name", name, "The scene's name (default: the scan file's stem)");
  app.add_option("--format", format, "The scan's format, as io.read_points' `format`")
      ->capture_default_str();
  app.add_option("--station", station_text,
                 "Where the scanner stood, x,y,z in the scan's coordinates and units: a scan from one "
                 "station exported without it (PLY, XYZ, PTS, LAS). It says which side was scanned: "
                 "the views look from it, and the scene declares it to io.read_points (`station`), "
                 "which orients the normals toward it");
  app.add_flag("--no-find-station", no_find_station,
               "Do not look in the points for where the scanner stood when the file has no station "
               "and the points enclose no room (by default the place found, if any, is declared as "
               "the scan's station)");
  app.add_flag("--force", force, "Replace an existing -o file");
  if (const std::optional<int> exit = ParseCommandArgs(app, args)) return *exit;

  auto fail = [](const std::string& message) {
    std::fprintf(stderr, "pointbake scene: %s\n", message.c_str());
    return 2;
  };
  SceneSurveyOptions options;
  if (!ParseVector(up_text, &options.up))
    return fail("--up " + up_text + ": expected three numbers x,y,z");
  std::array<double, 3> station{};
  if (!station_text.empty() && !ParseVector(station_text, &station))
    return fail("--station " + station_text + ": expected three numbers x,y,z");
  Env* env = Env::Default();
  if (!out_path.empty() && !force && env->Exists(out_path))
    return fail(out_path + " exists; give --force to replace it, or another -o");
  if (!env->Exists(scan_path)) return fail(scan_path + ": file not found");
  if (name.empty()) name = DefaultWorkflowName(scan_path);
  if (name.empty() || !std::isalnum(static_cast<unsigned char>(name[0]))) name = "scan_" + name;

  std::fprintf(stderr, "pointbake scene: reading %s\n", scan_path.c_str());
  ScanReadOptions read_options;
  read_options.drop_invalid_points = true;
  // A declared station replaces whatever the file's grid would show, as in
  // io.read_points.
  read_options.infer_stations = station_text.empty();
  Expected<ScanReadResult> read = ReadScan(scan_path, format, read_options);
  if (!read.ok()) return fail(read.status().message());
  for (const std::string& warning : read->warnings)
    std::fprintf(stderr, "warning: %s\n", warning.c_str());
  if (!station_text.empty())
    for (const std::string& warning : DeclareStation(station, &read->points))
      std::fprintf(stderr, "warning: %s\n", warning.c_str());
  const double unit_m = *MetersPerUnit(units);
  ConvertToMeters(unit_m, &read->points);
  std::fprintf(stderr, "pointbake scene: surveying %s points\n",
               WithThousands(read->points.size()).c_str());
  Expected<SceneSurvey> survey = SurveyScene(read->points, options);
  if (!survey.ok()) return fail(scan_path + ": " + survey.status().message());
  for (const std::string& warning : survey->warnings)
    std::fprintf(stderr, "warning: %s\n", warning.c_str());
  // No station and no room around the points: one scan exported without its
  // position, perhaps. Its points tell where it stood (lost_station.h); the
  // scene declares that place as the file's station, as --station would.
  std::string station_found, station_sought;
  // A room closed in is not one scan's; one nearly closed may be (a cell
  // scanned from its middle), and a station found says more.
  if (station_text.empty() && !no_find_station && survey->stations == 0 &&
      (!(survey->enclosed_volume_m3 > 0) || survey->enclosure_open)) {
    std::fprintf(stderr, "pointbake scene: looking in the points for where the scanner stood\n");
    LostStationOptions lost_options;
    lost_options.up = options.up;
    Expected<LostStation> lost = FindLostStation(read->points, lost_options);
    if (!lost.ok()) return fail(scan_path + ": " + lost.status().message());
    if (lost->found) {
      std::array<double, 3> at;  // to a millimetre: the search is good to about a decimetre
      for (int a = 0; a < 3; ++a) at[a] = std::round(lost->position[a] * 1000) / 1000;
      for (const std::string& warning : DeclareStation(at, &read->points))
        std::fprintf(stderr, "warning: %s\n", warning.c_str());
      survey = SurveyScene(read->points, options);
      if (!survey.ok()) return fail(scan_path + ": " + survey.status().message());
      station_text = Vector(at, unit_m);
      station_text = station_text.substr(1, station_text.size() - 2);
      station_found = lost->figures;
      std::fprintf(stderr,
                   "note: no scanner station in the file, but %s: the scanner stood at %s (the file's "
                   "coordinates and units; %s). The scene declares it as the scan's station, so that the "
                   "normals and the views face the side it scanned. Check it: give --station x,y,z if "
                   "you know better, or --no-find-station\n",
                   lost->verdict.c_str(), station_text.c_str(), lost->figures.c_str());
    } else {
      station_sought = lost->verdict + " (" + lost->figures + ")";
    }
  }
  if (survey->stations == 0 && !(survey->enclosed_volume_m3 > 0))
    std::fprintf(stderr,
                 "note: no scanner station%s: if this is one scan exported without its position, give "
                 "--station x,y,z (where the scanner stood, in the file's coordinates and units), so "
                 "that the normals and the views face the side it scanned\n",
                 station_sought.empty() ? "" : (" (" + station_sought + ")").c_str());
  if (units == "m" && survey->spacing_m > 0.2)
    std::fprintf(stderr,
                 "warning: the median spacing is %s, more than a scanner leaves: if the file is in "
                 "millimetres (or cm, ft, in), give --units mm\n",
                 Length(survey->spacing_m).c_str());

  std::string scan_in_file = fs::absolute(scan_path).lexically_normal().string();
  if (!out_path.empty()) {
    const fs::path folder = fs::absolute(out_path).parent_path();
    scan_in_file = fs::absolute(scan_path).lexically_normal().lexically_relative(folder).string();
  }
  // The station as given, to 15 digits: a georeferenced position in
  // millimetres has 10 or more before the point.
  std::string station_yaml = station_text;
  if (station_found.empty() && !station_text.empty()) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "%.15g, %.15g, %.15g", station[0], station[1], station[2]);
    station_yaml = buf;
  }
  const std::string yaml =
      SceneYaml(name, scan_in_file, scan_path, units, unit_m, *read, *survey, station_yaml, station_found);
  if (out_path.empty()) {
    std::fputs(yaml.c_str(), stdout);
    return 0;
  }
  const std::string folder = fs::absolute(out_path).parent_path().string();
  if (Status st = env->CreateDirs(folder); !st.ok()) return fail(st.message());
  // Loaded as the workflows will load it (beside its final name, for the
  // relative path) before it replaces anything.
  const std::string checked = TempNameFor(out_path);
  if (Status st = env->WriteFileAtomic(checked, yaml); !st.ok())
    return fail(out_path + ": " + st.message());
  Expected<nlohmann::json> loaded = LoadScene(checked);
  if (!loaded.ok()) {
    (void)env->RemoveAll(checked);
    return fail("the scene does not load (a bug; nothing written): " + loaded.status().message());
  }
  if (Status st = env->Rename(checked, out_path); !st.ok()) {
    (void)env->RemoveAll(checked);
    return fail(out_path + ": " + st.message());
  }
  std::fprintf(
      stderr, "pointbake scene: wrote %s (%zu viewpoints; depth %d / %d, %lld / %lld faces)\n",
      out_path.c_str(), survey->viewpoints.size(), survey->depth_high, survey->depth_low,
      static_cast<long long>(survey->faces_high), static_cast<long long>(survey->faces_low));
  return 0;
}

}  // namespace

CliCommand SceneCommand() {
  return {"scene", "Write a scene file (viewpoints, parameters) for your own scan", &RunScene};
}

}  // namespace pb
