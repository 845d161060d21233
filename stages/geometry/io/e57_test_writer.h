// E57 test support, for tests only (no production code includes it): a
// minimal writer for hand-made test files: header, one CompressedVector
// section per scan (bitPackCodec, streams split across small packets so
// values straddle packet boundaries), XML, CRC-checked pages. Used by the
// reader's tests (io/e57_test.cc) and by stage tests that need an E57.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "stages/geometry/io/e57_binary.h"

namespace pb::testing {

struct TestField {
  enum class Kind { kFloat32, kFloat64, kInteger, kScaledInteger };
  std::string name;
  Kind kind = Kind::kFloat64;
  int64_t minimum = 0;
  int64_t maximum = 0;
  double scale = 1.0;
  double offset = 0.0;
  std::vector<double> values;  // floats as is; integers as raw integer values

  std::string Xml() const {
    std::ostringstream out;
    out.precision(17);
    out << "<" << name;
    switch (kind) {
      case Kind::kFloat32:
        out << " type=\"Float\" precision=\"single\"";
        break;
      case Kind::kFloat64:
        out << " type=\"Float\"";
        break;
      case Kind::kInteger:
        out << " type=\"Integer\" minimum=\"" << minimum << "\" maximum=\"" << maximum << "\"";
        break;
      case Kind::kScaledInteger:
        out << " type=\"ScaledInteger\" minimum=\"" << minimum << "\" maximum=\"" << maximum
            << "\" scale=\"" << scale << "\" offset=\"" << offset << "\"";
        break;
    }
    out << "/>";
    return out.str();
  }

  std::vector<uint8_t> Stream() const {
    std::vector<uint8_t> bytes;
    if (kind == Kind::kFloat32 || kind == Kind::kFloat64) {
      for (double v : values) {
        uint8_t raw[8];
        size_t size = 8;
        if (kind == Kind::kFloat32) {
          const float f = static_cast<float>(v);
          std::memcpy(raw, &f, 4);
          size = 4;
        } else {
          std::memcpy(raw, &v, 8);
        }
        bytes.insert(bytes.end(), raw, raw + size);
      }
      return bytes;
    }
    const int bits = std::bit_width(static_cast<uint64_t>(maximum - minimum));
    uint64_t bit_pos = 0;
    for (double v : values) {
      const uint64_t packed = static_cast<uint64_t>(std::llround(v) - minimum);
      for (int b = 0; b < bits; ++b, ++bit_pos) {
        if (bit_pos / 8 >= bytes.size()) bytes.push_back(0);
        if ((packed >> b) & 1) bytes[bit_pos / 8] |= static_cast<uint8_t>(1u << (bit_pos % 8));
      }
    }
    return bytes;
  }
};

inline TestField Float64(const std::string& name, std::vector<double> values) {
  return {name, TestField::Kind::kFloat64, 0, 0, 1.0, 0.0, std::move(values)};
}
inline TestField Float32(const std::string& name, std::vector<double> values) {
  return {name, TestField::Kind::kFloat32, 0, 0, 1.0, 0.0, std::move(values)};
}
inline TestField Integer(const std::string& name, int64_t minimum, int64_t maximum,
                         std::vector<double> values) {
  return {name, TestField::Kind::kInteger, minimum, maximum, 1.0, 0.0, std::move(values)};
}
inline TestField Scaled(const std::string& name, int64_t minimum, int64_t maximum, double scale,
                        double offset, std::vector<double> values) {
  return {
      name, TestField::Kind::kScaledInteger, minimum, maximum, scale, offset, std::move(values)};
}

struct TestScan {
  std::vector<TestField> fields;
  std::string extra_xml;      // pose, colorLimits, ... inside <vectorChild>
  std::string codecs_xml;     // children of <codecs>
  int64_t record_count = -1;  // -1: the first field's value count
  int64_t file_offset = -1;   // -1: the real section offset
};

struct WriterOptions {
  size_t stream_bytes_per_packet = 7;  // small, odd: values straddle packets
  bool empty_and_index_packets = true;
  int packet_type = 1;
  uint32_t version_major = 1;
  std::function<void(std::string*)> edit_xml;  // patches the XML text
};

inline void PutLe(std::vector<uint8_t>* out, size_t at, uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) (*out)[at + i] = static_cast<uint8_t>(value >> (8 * i));
}
inline void AppendLe(std::vector<uint8_t>* out, uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) out->push_back(static_cast<uint8_t>(value >> (8 * i)));
}

inline void AppendPacket(std::vector<uint8_t>* logical, int type,
                         const std::vector<uint8_t>& body) {
  const size_t start = logical->size();
  logical->push_back(static_cast<uint8_t>(type));
  logical->push_back(0);
  AppendLe(logical, 0, 2);  // length, patched below
  logical->insert(logical->end(), body.begin(), body.end());
  while ((logical->size() - start) % 4 != 0) logical->push_back(0);
  PutLe(logical, start + 2, logical->size() - start - 1, 2);
}

inline std::vector<uint8_t> BuildE57(const std::vector<TestScan>& scans,
                                     const WriterOptions& options = {}) {
  std::vector<uint8_t> logical(48, 0);
  std::string scans_xml;
  for (const TestScan& scan : scans) {
    const size_t section_start = logical.size();
    logical.resize(section_start + 32, 0);
    std::vector<std::vector<uint8_t>> streams;
    for (const TestField& field : scan.fields) streams.push_back(field.Stream());
    std::vector<size_t> sent(streams.size(), 0);
    bool first = true;
    while (first || [&] {
      for (size_t s = 0; s < streams.size(); ++s) {
        if (sent[s] < streams[s].size()) return true;
      }
      return false;
    }()) {
      if (!first && options.empty_and_index_packets) AppendPacket(&logical, 2, {});
      first = false;
      std::vector<uint8_t> body;
      AppendLe(&body, streams.size(), 2);
      std::vector<size_t> take(streams.size());
      for (size_t s = 0; s < streams.size(); ++s) {
        take[s] = std::min(options.stream_bytes_per_packet, streams[s].size() - sent[s]);
        AppendLe(&body, take[s], 2);
      }
      for (size_t s = 0; s < streams.size(); ++s) {
        body.insert(body.end(), streams[s].begin() + sent[s],
                    streams[s].begin() + sent[s] + take[s]);
        sent[s] += take[s];
      }
      AppendPacket(&logical, options.packet_type, body);
    }
    if (options.empty_and_index_packets) {
      std::vector<uint8_t> index_body(12, 0);  // entryCount 0, indexLevel 0, reserved
      AppendPacket(&logical, 0, index_body);
    }
    logical[section_start] = 1;
    PutLe(&logical, section_start + 8, logical.size() - section_start, 8);
    PutLe(&logical, section_start + 16, e57::LogicalToPhysical(section_start + 32), 8);

    const int64_t records = scan.record_count >= 0
                                ? scan.record_count
                                : static_cast<int64_t>(scan.fields.at(0).values.size());
    const int64_t offset = scan.file_offset >= 0
                               ? scan.file_offset
                               : static_cast<int64_t>(e57::LogicalToPhysical(section_start));
    scans_xml += "    <vectorChild type=\"Structure\">\n      " + scan.extra_xml +
                 "\n      <points type=\"CompressedVector\" fileOffset=\"" +
                 std::to_string(offset) + "\" recordCount=\"" + std::to_string(records) +
                 "\">\n        <prototype type=\"Structure\">\n";
    for (const TestField& field : scan.fields) scans_xml += "          " + field.Xml() + "\n";
    scans_xml +=
        "        </prototype>\n        <codecs type=\"Vector\" allowHeterogeneousChildren=\"1\">" +
        scan.codecs_xml + "</codecs>\n      </points>\n    </vectorChild>\n";
  }
  std::string xml =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<e57Root type=\"Structure\" xmlns=\"http://www.astm.org/COMMIT/E57/2010-e57-v1.0\">\n"
      "  <formatName type=\"String\"><![CDATA[ASTM E57 3D Imaging Data File]]></formatName>\n"
      "  <!-- written by e57_test -->\n"
      "  <data3D type=\"Vector\" allowHeterogeneousChildren=\"1\">\n" +
      scans_xml + "  </data3D>\n</e57Root>\n";
  if (options.edit_xml) options.edit_xml(&xml);
  const size_t xml_start = logical.size();
  logical.insert(logical.end(), xml.begin(), xml.end());

  const size_t pages = (logical.size() + 1019) / 1020;
  std::memcpy(logical.data(), "ASTM-E57", 8);
  PutLe(&logical, 8, options.version_major, 4);
  PutLe(&logical, 12, 0, 4);
  PutLe(&logical, 16, pages * 1024, 8);
  PutLe(&logical, 24, e57::LogicalToPhysical(xml_start), 8);
  PutLe(&logical, 32, xml.size(), 8);
  PutLe(&logical, 40, 1024, 8);
  logical.resize(pages * 1020, 0);
  std::vector<uint8_t> file;
  for (size_t p = 0; p < pages; ++p) {
    file.insert(file.end(), logical.begin() + p * 1020, logical.begin() + (p + 1) * 1020);
    const uint32_t crc = e57::Crc32c(logical.data() + p * 1020, 1020);
    for (int shift = 24; shift >= 0; shift -= 8) file.push_back(static_cast<uint8_t>(crc >> shift));
  }
  return file;
}

}  // namespace pb::testing
