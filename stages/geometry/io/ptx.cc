#include "stages/geometry/io/ptx.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>

#include "stages/geometry/core/buffered_input.h"
#include "stages/geometry/core/text_parse.h"

namespace pb {
namespace {

bool IsBlank(std::string_view line) {
  return line.find_first_not_of(" \t\r\f\v") == std::string_view::npos;
}

std::string Quote(std::string_view text) {
  constexpr size_t kMaxShown = 60;
  std::string shown(text.substr(0, kMaxShown));
  if (text.size() > kMaxShown) shown += "...";
  return "'" + shown + "'";
}

uint8_t ColorByte(double value) {
  if (!(value > 0)) return 0;
  if (value >= 255) return 255;
  return static_cast<uint8_t>(std::lround(value));
}

struct ScanHeader {
  uint64_t columns = 0;
  uint64_t rows = 0;
  std::array<double, 3> position{};
  std::array<std::array<double, 4>, 4> matrix{};  // as written: matrix[row][column]
};

class PtxParser {
 public:
  PtxParser(const std::string& path, const ScanReadOptions& options)
      : path_(path), options_(options) {}

  Expected<ScanReadResult> Run() {
    PB_RETURN_IF_ERROR(in_.Open(path_, "a PTX file", &options_.progress));
    PointCloud& cloud = result_.points;
    uint64_t scan_count = 0;
    while (true) {
      std::string_view line;
      if (!NextNonBlank(&line)) {
        PB_RETURN_IF_ERROR(InputStatus());
        break;
      }
      if (scan_count == kMaxScans) {
        return Status::Unsupported(Where() + ": more than " + std::to_string(kMaxScans) +
                                   " scans in one file");
      }
      ScanHeader header;
      PB_RETURN_IF_ERROR(ParseHeader(line, &header));
      cloud.stations.push_back(header.position);
      PB_RETURN_IF_ERROR(ReadPoints(header, scan_count));
      ++scan_count;
    }
    if (scan_count == 0) {
      return Status::Invalid(path_ + ": empty file, expected a PTX header (the column count)");
    }
    if (mixed_colors_) {
      cloud.colors.clear();
      cloud.colors.shrink_to_fit();
      result_.warnings.push_back("some scans have colors and some do not; colors dropped");
    }
    if (clamped_intensities_ > 0) {
      result_.warnings.push_back(std::to_string(clamped_intensities_) +
                                 " intensities outside [0, 1] clamped");
    }
    if (scan_count > 1) result_.warnings.push_back(std::to_string(scan_count) + " scans merged");
    result_.format = "ptx";
    if (options_.progress) options_.progress(1.0);
    return std::move(result_);
  }

 private:
  static constexpr uint64_t kMaxScans = 65536;  // station_ids are uint16
  static constexpr uint64_t kMaxGridSide = uint64_t{1} << 31;
  // Farther than this from the origin, float32 positions are meaningless (and
  // the cast could overflow): the file is not a scan.
  static constexpr double kMaxSpanM = 1e8;

  std::string Where() const { return path_ + ":" + std::to_string(in_.line_number()); }

  // Why the last NextNonBlank returned false, if not the end of the file.
  Status InputStatus() const {
    PB_RETURN_IF_ERROR(in_.error());
    if (in_.line_too_long()) {
      return Status::Invalid(path_ + ":" + std::to_string(in_.line_number() + 1) +
                             ": line longer than 1 MiB; not a PTX file?");
    }
    return Status::Ok();
  }

  bool NextNonBlank(std::string_view* line) {
    while (in_.ReadLine(line)) {
      if (!IsBlank(*line)) return true;
    }
    return false;
  }

  // Reads the next non-blank line as exactly `count` finite numbers.
  Status ReadNumbers(size_t count, const char* what, double* values) {
    std::string_view line;
    if (!NextNonBlank(&line)) {
      PB_RETURN_IF_ERROR(InputStatus());
      return Status::Invalid(Where() + ": truncated header: expected " + what);
    }
    return ParseNumbers(line, count, what, values);
  }

  Status ParseNumbers(std::string_view line, size_t count, const char* what, double* values) {
    std::string_view words[4];
    const size_t found = SplitWords(line, words, count);
    if (found != count) {
      return Status::Invalid(Where() + ": expected " + what + " (" + std::to_string(count) +
                             " numbers), found " + Quote(line));
    }
    for (size_t i = 0; i < count; ++i) {
      if (!ParseDouble(words[i], &values[i]) || !std::isfinite(values[i])) {
        return Status::Invalid(Where() + ": expected " + what + ", found " + Quote(words[i]));
      }
    }
    return Status::Ok();
  }

  Status ParseGridSide(std::string_view line, const char* what, uint64_t* value) {
    std::string_view words[1];
    bool ok = SplitWords(line, words, 1) == 1;
    ok = ok && ParseUint(words[0], value) && *value > 0 && *value <= kMaxGridSide;
    if (!ok) {
      return Status::Invalid(Where() + ": expected the " + what +
                             " count (a positive integer), found " + Quote(line));
    }
    return Status::Ok();
  }

  Status ParseHeader(std::string_view columns_line, ScanHeader* header) {
    PB_RETURN_IF_ERROR(ParseGridSide(columns_line, "column", &header->columns));
    std::string_view line;
    if (!NextNonBlank(&line)) {
      PB_RETURN_IF_ERROR(InputStatus());
      return Status::Invalid(Where() + ": truncated header: expected the row count");
    }
    PB_RETURN_IF_ERROR(ParseGridSide(line, "row", &header->rows));
    PB_RETURN_IF_ERROR(ReadNumbers(3, "the scanner position x y z", header->position.data()));
    std::array<double, 3> axis;
    for (int i = 0; i < 3; ++i) {
      PB_RETURN_IF_ERROR(ReadNumbers(3, "a scanner axis x y z", axis.data()));
    }
    for (int row = 0; row < 4; ++row) {
      PB_RETURN_IF_ERROR(ReadNumbers(4, "a transformation matrix row", header->matrix[row].data()));
      const double expected = row == 3 ? 1.0 : 0.0;
      if (std::abs(header->matrix[row][3] - expected) > 1e-6) {
        return Status::Invalid(
            Where() + ": transformation matrix row " + std::to_string(row + 1) + " must end in " +
            (row == 3 ? "1" : "0") +
            " (PTX matrices are row-major with the translation in the 4th row); a column-major "
            "matrix is not supported");
      }
    }
    return Status::Ok();
  }

  // Grows the output arrays ahead of a scan, bounded by what the rest of the
  // file can hold so that a lying header cannot allocate terabytes.
  void Reserve(uint64_t count, bool colors) {
    constexpr uint64_t kMinBytesPerPoint = 8;  // "0 0 0 0\n"
    const uint64_t remaining = in_.remaining();
    PointCloud& cloud = result_.points;
    const size_t target = cloud.size() + std::min(count, remaining / kMinBytesPerPoint);
    if (target <= cloud.size() || target * 3 <= cloud.positions.capacity()) return;
    const size_t grown = std::max(target, cloud.size() + cloud.size() / 2);
    cloud.positions.reserve(grown * 3);
    cloud.intensities.reserve(grown);
    cloud.station_ids.reserve(grown);
    if (colors) cloud.colors.reserve(grown * 3);
  }

  Status ReadPoints(const ScanHeader& header, uint64_t scan_index) {
    PointCloud& cloud = result_.points;
    const uint64_t count = header.columns * header.rows;
    const auto& m = header.matrix;
    size_t values_per_line = 0;  // 4 or 7, decided by the scan's first point line
    int64_t first_line = 0;
    for (uint64_t i = 0; i < count; ++i) {
      std::string_view line;
      if (!NextNonBlank(&line)) {
        PB_RETURN_IF_ERROR(InputStatus());
        return Status::Invalid(Where() + ": truncated: scan " + std::to_string(scan_index + 1) +
                               " ends after " + std::to_string(i) + " of " + std::to_string(count) +
                               " points (" + std::to_string(header.columns) + " columns x " +
                               std::to_string(header.rows) + " rows)");
      }
      std::string_view words[7];
      const size_t found = SplitWords(line, words, 7);
      if (values_per_line == 0) {
        if (found != 4 && found != 7) {
          return Status::Invalid(Where() +
                                 ": expected 4 values (x y z intensity) or 7 (x y z intensity "
                                 "r g b), found " +
                                 (found > 7 ? "more" : std::to_string(found)));
        }
        values_per_line = found;
        first_line = in_.line_number();
        const bool colored = found == 7;
        if (scan_index == 0) {
          any_colors_ = colored;
        } else if (colored != any_colors_) {
          mixed_colors_ = true;
          any_colors_ = any_colors_ || colored;
        }
        Reserve(count - i, colored && !mixed_colors_);
      } else if (found != values_per_line) {
        return Status::Invalid(Where() + ": expected " + std::to_string(values_per_line) +
                               " values like line " + std::to_string(first_line) + ", found " +
                               (found > 7 ? "more" : std::to_string(found)));
      }
      double v[7];
      bool finite = true;
      for (size_t k = 0; k < found; ++k) {
        if (!ParseDouble(words[k], &v[k])) {
          return Status::Invalid(Where() + ": value " + std::to_string(k + 1) +
                                 " is not a number: " + Quote(words[k]));
        }
        finite = finite && std::isfinite(v[k]);
      }
      if (!finite) {
        if (options_.drop_invalid_points) {
          ++result_.dropped_points;
          continue;
        }
        return Status::Invalid(Where() + ": point " + std::to_string(i + 1) + " of scan " +
                               std::to_string(scan_index + 1) +
                               " has a NaN or infinite value (set drop_invalid_points to skip "
                               "such points)");
      }
      if (v[0] == 0 && v[1] == 0 && v[2] == 0) {  // no return
        ++result_.no_return_points;
        continue;
      }
      std::array<double, 3> p;
      for (int c = 0; c < 3; ++c) {
        p[c] = v[0] * m[0][c] + v[1] * m[1][c] + v[2] * m[2][c] + m[3][c];
      }
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
        return Status::Invalid(Where() + ": point " + std::to_string(i + 1) + " of scan " +
                               std::to_string(scan_index + 1) +
                               " overflows when transformed by the scan's matrix");
      }
      if (!have_origin_) {
        for (int c = 0; c < 3; ++c) cloud.origin[c] = std::round(p[c]);
        have_origin_ = true;
      }
      for (int c = 0; c < 3; ++c) p[c] -= cloud.origin[c];
      if (std::max({std::abs(p[0]), std::abs(p[1]), std::abs(p[2])}) > kMaxSpanM) {
        return Status::Invalid(Where() + ": point " + std::to_string(i + 1) + " of scan " +
                               std::to_string(scan_index + 1) +
                               " lies more than 1e8 m from the file's first point");
      }
      for (int c = 0; c < 3; ++c) cloud.positions.push_back(static_cast<float>(p[c]));
      double intensity = v[3];
      if (intensity < 0 || intensity > 1) {
        ++clamped_intensities_;
        intensity = std::clamp(intensity, 0.0, 1.0);
      }
      cloud.intensities.push_back(static_cast<float>(intensity));
      cloud.station_ids.push_back(static_cast<uint16_t>(scan_index));
      if (values_per_line == 7 && !mixed_colors_) {
        cloud.colors.push_back(ColorByte(v[4]));
        cloud.colors.push_back(ColorByte(v[5]));
        cloud.colors.push_back(ColorByte(v[6]));
      }
    }
    return Status::Ok();
  }

  const std::string& path_;
  const ScanReadOptions& options_;
  BufferedInput in_;  // longest line: 1 MiB
  ScanReadResult result_;
  bool have_origin_ = false;
  bool any_colors_ = false;
  bool mixed_colors_ = false;
  uint64_t clamped_intensities_ = 0;
};

}  // namespace

Expected<ScanReadResult> ReadPtx(const std::string& path, const ScanReadOptions& options) {
  return PtxParser(path, options).Run();
}

}  // namespace pb
