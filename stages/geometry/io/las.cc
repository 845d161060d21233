#include "stages/geometry/io/las.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <type_traits>
#include <vector>

#include "stages/geometry/core/buffered_input.h"
#include "stages/geometry/io/laz.h"

namespace pb {
namespace {

constexpr size_t kMinHeaderBytes = 227;  // LAS 1.0-1.2
constexpr size_t kHeader14Bytes = 375;   // LAS 1.4
// Farther than this from the origin, float32 positions are meaningless (and
// the cast could overflow): the header's scale or offset is garbage.
constexpr double kMaxSpanM = 1e8;

// Little-endian loads, independent of the host's byte order.
template <typename T>
T Load(const uint8_t* bytes) {
  using Unsigned = std::conditional_t<
      sizeof(T) == 1, uint8_t,
      std::conditional_t<sizeof(T) == 2, uint16_t,
                         std::conditional_t<sizeof(T) == 4, uint32_t, uint64_t>>>;
  Unsigned value = 0;
  for (size_t i = 0; i < sizeof(T); ++i) value |= static_cast<Unsigned>(bytes[i]) << (8 * i);
  return std::bit_cast<T>(value);
}

// Where the fields we read sit in a point record; -1 = absent.
struct PointLayout {
  size_t record_bytes;  // the format's standard size
  int rgb_offset;
};

bool LayoutOf(int format, PointLayout* layout) {
  static constexpr PointLayout kLayouts[] = {
      {20, -1}, {28, -1}, {26, 20}, {34, 28}, {57, -1}, {63, 28},
      {30, -1}, {36, 30}, {38, 30}, {59, -1}, {67, 30},
  };
  if (format < 0 || format > 10) return false;
  *layout = kLayouts[format];
  return true;
}

struct LasHeader {
  int version_major = 0;
  int version_minor = 0;
  size_t header_bytes = 0;
  uint64_t point_offset = 0;
  int point_format = 0;
  size_t record_bytes = 0;
  uint64_t point_count = 0;
  std::array<double, 3> scale{};
  std::array<double, 3> offset{};
  std::array<double, 3> min{};
  std::array<double, 3> max{};
  uint32_t vlr_count = 0;
};

constexpr size_t kVlrHeaderBytes = 54;
constexpr uint16_t kLaszipRecordId = 22204;

class LasReader {
 public:
  LasReader(const std::string& path, const ScanReadOptions& options)
      : path_(path), options_(options) {}

  Expected<ScanReadResult> Run() {
    PB_RETURN_IF_ERROR(in_.Open(path_, "a LAS file", &options_.progress));
    file_bytes_ = in_.size();

    PB_RETURN_IF_ERROR(ReadHeader());
    if (compressed_) {
      PB_RETURN_IF_ERROR(OpenLaz());
      PB_RETURN_IF_ERROR(ReadLazPoints());
    } else {
      PB_RETURN_IF_ERROR(ReadPoints());
    }
    result_.format = std::string(compressed_ ? laz_->description() : "las") + " " +
                     std::to_string(header_.version_major) + "." +
                     std::to_string(header_.version_minor) + " format " +
                     std::to_string(header_.point_format);
    if (options_.progress) options_.progress(1.0);
    return std::move(result_);
  }

 private:
  Status ReadHeader() {
    uint8_t bytes[kHeader14Bytes] = {};
    const size_t got = in_.ReadUpTo(bytes, sizeof bytes);
    PB_RETURN_IF_ERROR(in_.error());
    if (got < 4 || std::memcmp(bytes, "LASF", 4) != 0) {
      return Status::Invalid(path_ + ": not a LAS file (expected signature 'LASF' at byte 0)");
    }
    if (got < kMinHeaderBytes) {
      return Status::Corrupt(path_ + ": truncated header: " + std::to_string(got) +
                             " bytes, a LAS header has at least " +
                             std::to_string(kMinHeaderBytes));
    }
    LasHeader& h = header_;
    h.version_major = bytes[24];
    h.version_minor = bytes[25];
    if (h.version_major != 1 || h.version_minor > 4) {
      return Status::Unsupported(path_ + ": LAS version " + std::to_string(h.version_major) + "." +
                                 std::to_string(h.version_minor) +
                                 " is not supported (byte 24; expected 1.0 to 1.4)");
    }
    h.header_bytes = Load<uint16_t>(bytes + 94);
    if (h.header_bytes < kMinHeaderBytes) {
      return Status::Corrupt(path_ + ": header size " + std::to_string(h.header_bytes) +
                             " (byte 94) is smaller than the minimum " +
                             std::to_string(kMinHeaderBytes));
    }
    if (got < std::min(h.header_bytes, kHeader14Bytes)) {
      return Status::Corrupt(path_ + ": truncated header: " + std::to_string(got) +
                             " bytes, the header declares " + std::to_string(h.header_bytes));
    }
    h.point_offset = Load<uint32_t>(bytes + 96);
    if (h.point_offset < h.header_bytes) {
      return Status::Corrupt(path_ + ": offset to point data " + std::to_string(h.point_offset) +
                             " (byte 96) lies inside the " + std::to_string(h.header_bytes) +
                             "-byte header");
    }
    const uint8_t format_byte = bytes[104];
    compressed_ = (format_byte & 0xC0) != 0;  // LASzip sets bit 7 (older writers bit 6)
    h.point_format = format_byte & 0x3F;
    h.vlr_count = Load<uint32_t>(bytes + 100);
    PointLayout layout;
    if (!LayoutOf(h.point_format, &layout)) {
      return Status::Unsupported(path_ + ": point data record format " +
                                 std::to_string(h.point_format) +
                                 " (byte 104) is not defined by LAS 1.4 (formats 0 to 10)");
    }
    layout_ = layout;
    h.record_bytes = Load<uint16_t>(bytes + 105);
    if (h.record_bytes < layout.record_bytes) {
      return Status::Corrupt(path_ + ": point record length " + std::to_string(h.record_bytes) +
                             " (byte 105) is smaller than the " +
                             std::to_string(layout.record_bytes) + " bytes point format " +
                             std::to_string(h.point_format) + " needs");
    }
    h.point_count = Load<uint32_t>(bytes + 107);
    if (h.version_minor >= 4 && h.header_bytes >= kHeader14Bytes) {
      const uint64_t count64 = Load<uint64_t>(bytes + 247);
      if (count64 != 0) h.point_count = count64;
    }
    for (int axis = 0; axis < 3; ++axis) {
      h.scale[axis] = Load<double>(bytes + 131 + 8 * axis);
      h.offset[axis] = Load<double>(bytes + 155 + 8 * axis);
      h.max[axis] = Load<double>(bytes + 179 + 16 * axis);
      h.min[axis] = Load<double>(bytes + 187 + 16 * axis);
      if (!std::isfinite(h.scale[axis]) || h.scale[axis] == 0 || !std::isfinite(h.offset[axis])) {
        return Status::Corrupt(
            path_ + ": " + "xyz"[axis] + " scale " + std::to_string(h.scale[axis]) + " or offset " +
            std::to_string(h.offset[axis]) + " (bytes " + std::to_string(131 + 8 * axis) + ", " +
            std::to_string(155 + 8 * axis) + ") is not a finite non-zero number");
      }
    }
    // Fail before decoding anything if the points cannot all be there.
    if (compressed_) return Status::Ok();  // the chunk table says
    const uint64_t available = file_bytes_ - std::min(file_bytes_, h.point_offset);
    if (h.point_count > available / h.record_bytes) {
      return Truncated(available / h.record_bytes);
    }
    return Status::Ok();
  }

  Status Truncated(uint64_t point_index) const {
    return Status::Corrupt(
        path_ + ": truncated: point " + std::to_string(point_index) + " of " +
        std::to_string(header_.point_count) + " at byte " +
        std::to_string(header_.point_offset + point_index * header_.record_bytes) + " (file has " +
        std::to_string(file_bytes_) + " bytes)");
  }

  // The origin: the header's box center, unless the box is unusable.
  void ChooseOrigin(const std::array<double, 3>& first_point) {
    const LasHeader& h = header_;
    bool box_ok = true;
    for (int axis = 0; axis < 3; ++axis) {
      box_ok = box_ok && std::isfinite(h.min[axis]) && std::isfinite(h.max[axis]) &&
               h.min[axis] - 1 <= first_point[axis] && first_point[axis] <= h.max[axis] + 1;
    }
    for (int axis = 0; axis < 3; ++axis) {
      result_.points.origin[axis] =
          std::round(box_ok ? 0.5 * (h.min[axis] + h.max[axis]) : first_point[axis]);
    }
    if (!box_ok) {
      result_.warnings.push_back(
          "the header's bounding box does not contain the first point; origin taken from it");
    }
  }

  void AppendColor(const uint8_t* rgb) {
    std::vector<uint8_t>& colors = result_.points.colors;
    for (int channel = 0; channel < 3; ++channel) {
      const uint16_t value = Load<uint16_t>(rgb + 2 * channel);
      if (value > 255 && !colors_16bit_) {
        // Every earlier value was <= 255, i.e. 0 once shifted to 8 bits.
        colors_16bit_ = true;
        std::fill(colors.begin(), colors.end(), 0);
      }
      colors.push_back(static_cast<uint8_t>(colors_16bit_ ? value >> 8 : value));
    }
  }

  void Reserve() {
    const LasHeader& h = header_;
    PointCloud& cloud = result_.points;
    // The count is bounded by the file size (LAS) or checked against the
    // chunk table (LAZ).
    cloud.positions.reserve(3 * h.point_count);
    cloud.intensities.reserve(h.point_count);
    if (layout_.rgb_offset >= 0) cloud.colors.reserve(3 * h.point_count);
  }

  // Appends point `i` from its record; `byte` is where it sits (LAS) or
  // where its chunk starts (LAZ), for messages.
  Status AppendRecord(const uint8_t* record, uint64_t i, const std::string& where) {
    const LasHeader& h = header_;
    PointCloud& cloud = result_.points;
    std::array<double, 3> p;
    for (int axis = 0; axis < 3; ++axis) {
      p[axis] = Load<int32_t>(record + 4 * axis) * h.scale[axis] + h.offset[axis];
    }
    if (i == 0) ChooseOrigin(p);
    for (int axis = 0; axis < 3; ++axis) p[axis] -= cloud.origin[axis];
    if (!(std::max({std::abs(p[0]), std::abs(p[1]), std::abs(p[2])}) <= kMaxSpanM)) {
      return Status::Corrupt(path_ + ": point " + std::to_string(i) + where +
                             " lies more than 1e8 m from the origin; check the header's "
                             "scale and offset");
    }
    for (int axis = 0; axis < 3; ++axis) cloud.positions.push_back(static_cast<float>(p[axis]));
    cloud.intensities.push_back(static_cast<float>(Load<uint16_t>(record + 12) / 65535.0));
    if (layout_.rgb_offset >= 0) AppendColor(record + layout_.rgb_offset);
    return Status::Ok();
  }

  Status ReadPoints() {
    const LasHeader& h = header_;
    Reserve();
    if (!in_.Seek(h.point_offset)) return in_.error();
    std::vector<uint8_t> record_bytes(h.record_bytes);
    for (uint64_t i = 0; i < h.point_count; ++i) {
      if (!in_.Read(record_bytes.data(), h.record_bytes)) {
        PB_RETURN_IF_ERROR(in_.error());
        return Truncated(i);
      }
      PB_RETURN_IF_ERROR(
          AppendRecord(record_bytes.data(), i,
                       " at byte " + std::to_string(h.point_offset + i * h.record_bytes)));
    }
    return Status::Ok();
  }

  // Finds the laszip VLR among the VLRs between the header and the points.
  Status OpenLaz() {
    const LasHeader& h = header_;
    uint64_t offset = h.header_bytes;
    for (uint32_t i = 0; i < h.vlr_count; ++i) {
      uint8_t vlr_header[kVlrHeaderBytes];
      if (offset + kVlrHeaderBytes > h.point_offset || !in_.Seek(offset) ||
          !in_.Read(vlr_header, kVlrHeaderBytes)) {
        PB_RETURN_IF_ERROR(in_.error());
        return Status::Corrupt(path_ + ": VLR " + std::to_string(i) + " of " +
                               std::to_string(h.vlr_count) + " (byte " + std::to_string(offset) +
                               ", count at byte 100) does not fit before the point data at byte " +
                               std::to_string(h.point_offset));
      }
      const uint16_t record_id = Load<uint16_t>(vlr_header + 18);
      const uint16_t payload_bytes = Load<uint16_t>(vlr_header + 20);
      const uint64_t payload_offset = offset + kVlrHeaderBytes;
      if (payload_offset + payload_bytes > h.point_offset) {
        return Status::Corrupt(path_ + ": VLR " + std::to_string(i) + " at byte " +
                               std::to_string(offset) + " has " + std::to_string(payload_bytes) +
                               " bytes, more than lie before the point data at byte " +
                               std::to_string(h.point_offset));
      }
      if (std::memcmp(vlr_header + 2, "laszip encoded", 14) == 0 && record_id == kLaszipRecordId) {
        std::vector<uint8_t> payload(payload_bytes);
        if (!in_.Read(payload.data(), payload.size())) {
          PB_RETURN_IF_ERROR(in_.error());
          return Status::Corrupt(path_ + ": truncated: laszip VLR at byte " +
                                 std::to_string(offset) + " (file has " +
                                 std::to_string(file_bytes_) + " bytes)");
        }
        LazPointLayout layout{h.point_offset, h.point_count, h.point_format, h.record_bytes};
        auto laz = LazReader::Open(&in_, path_, layout, payload, payload_offset, {});
        if (!laz.ok()) return laz.status();
        laz_ = std::move(*laz);
        return Status::Ok();
      }
      offset = payload_offset + payload_bytes;
    }
    return Status::Corrupt(path_ + ": compressed point format " + std::to_string(h.point_format) +
                           " (byte 104 has a compression bit, 0x80 or 0x40, set) but none of the " +
                           std::to_string(h.vlr_count) +
                           " VLRs is the laszip VLR (user id \"laszip encoded\", record id 22204)");
  }

  Status ReadLazPoints() {
    Reserve();
    uint64_t i = 0;
    const std::string chunk_note = " (LAZ)";
    for (;;) {
      std::span<const uint8_t> records;
      PB_RETURN_IF_ERROR(laz_->Next(&records));
      if (records.empty()) break;
      for (size_t at = 0; at < records.size(); at += header_.record_bytes, ++i) {
        PB_RETURN_IF_ERROR(AppendRecord(records.data() + at, i, chunk_note));
      }
      if (options_.progress) options_.progress(static_cast<double>(i) / header_.point_count);
    }
    return Status::Ok();
  }

  const std::string& path_;
  const ScanReadOptions& options_;
  BufferedInput in_;
  uint64_t file_bytes_ = 0;
  LasHeader header_;
  PointLayout layout_{};
  bool colors_16bit_ = false;
  bool compressed_ = false;
  std::unique_ptr<LazReader> laz_;
  ScanReadResult result_;
};

}  // namespace

Expected<ScanReadResult> ReadLas(const std::string& path, const ScanReadOptions& options) {
  return LasReader(path, options).Run();
}

}  // namespace pb
