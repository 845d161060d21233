// The binary layers of an E57 file (ASTM E2807-11, sections 8-9): CRC-checked
// pages, the physical/logical offset mapping, and CompressedVector binary
// sections decoded with the bitPackCodec.
//
// Paging: the file is a sequence of 1024-byte pages, each 1020 bytes of data
// followed by the CRC-32C (Castagnoli, reflected polynomial 0x82F63B78) of
// those 1020 bytes, stored big-endian. "Logical" offsets count data bytes
// only; E57 stores "physical" offsets (into the file):
//   physical = (logical / 1020) * 1024 + logical % 1020.
// Every page read is verified; a mismatch is reported as
//   scan.e57: CRC-32C mismatch in page 12 (byte 12288)
// with the 0-based page index and the page's physical byte offset. Building
// with -DPB_E57_FUZZ_SKIP_CRC (fuzz targets only) skips the check so random
// inputs reach the decoders behind it.
//
// CompressedVector binary section (at the XML `fileOffset`, physical), all
// integers little-endian, all offsets physical, lengths logical:
//   uint8  sectionId = 1, uint8 reserved[7]
//   uint64 sectionLogicalLength   (header + packets)
//   uint64 dataPhysicalOffset     (first data packet)
//   uint64 indexPhysicalOffset    (0 or the index packet; not needed)
// then packets, each starting with uint8 packetType and, at byte 2, uint16
// packetLogicalLengthMinus1:
//   type 1 (data):  uint8 flags, uint16 lengthMinus1, uint16 bytestreamCount,
//                   uint16 bufferLength[bytestreamCount], then the buffers;
//   type 0 (index), type 2 (empty): skipped.
// Bytestream k holds prototype field k (depth-first order). bitPackCodec:
// Float fields are raw IEEE 754 little-endian (4 or 8 bytes); Integer and
// ScaledInteger fields pack (value - minimum) in ceil(log2(max - min + 1))
// bits, least significant bit first, as one continuous bit stream per field
// that runs on across packets (a value may straddle two packets).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "base/status.h"

namespace pb::e57 {

inline constexpr uint64_t kPageBytes = 1024;
inline constexpr uint64_t kPageDataBytes = 1020;

uint32_t Crc32c(const uint8_t* data, size_t size);

inline uint64_t LogicalToPhysical(uint64_t logical) {
  return logical / kPageDataBytes * kPageBytes + logical % kPageDataBytes;
}
// False if `physical` points into a page's CRC (not a valid data offset).
inline bool PhysicalToLogical(uint64_t physical, uint64_t* logical) {
  if (physical % kPageBytes >= kPageDataBytes) return false;
  *logical = physical / kPageBytes * kPageDataBytes + physical % kPageBytes;
  return true;
}

// Reads the logical byte stream of a paged file through a 256-page cache,
// verifying the CRC of every page it loads. Errors name `path`.
class PagedReader {
 public:
  static constexpr uint64_t kCachePages = 256;

  PagedReader() = default;
  ~PagedReader();
  PagedReader(const PagedReader&) = delete;
  PagedReader& operator=(const PagedReader&) = delete;

  Status Open(const std::string& path);
  const std::string& path() const { return path_; }
  uint64_t file_bytes() const { return file_bytes_; }
  // Logical bytes available in whole pages.
  uint64_t logical_bytes() const { return file_bytes_ / kPageBytes * kPageDataBytes; }
  // Bytes loaded from disk so far (for progress).
  uint64_t bytes_loaded() const { return bytes_loaded_; }

  // Reads the first `size` raw bytes of the file (no CRC; for the signature).
  Status ReadRaw(size_t size, uint8_t* out);
  // Reads `size` logical bytes starting at logical offset `logical`.
  Status Read(uint64_t logical, size_t size, uint8_t* out);

 private:
  Status LoadPages(uint64_t first_page);

  std::string path_;
  int fd_ = -1;
  uint64_t file_bytes_ = 0;
  uint64_t bytes_loaded_ = 0;
  std::vector<uint8_t> cache_;
  uint64_t cache_first_page_ = 0;
  uint64_t cache_pages_ = 0;
};

// How one prototype field is stored in its bytestream.
struct FieldCodec {
  enum class Kind { kFloat32, kFloat64, kInteger, kScaledInteger };
  Kind kind = Kind::kFloat64;
  int64_t minimum = 0;  // Integer/ScaledInteger raw bounds
  int64_t maximum = 0;
  double scale = 1.0;  // ScaledInteger: value = raw * scale + offset
  double offset = 0.0;

  // Bits per value in the bytestream: 32/64 for floats, 0..64 for integers.
  int BitsPerValue() const;
};

struct CompressedVectorSpec {
  std::string name;                      // for messages, e.g. "data3D scan 0 points"
  uint64_t section_physical_offset = 0;  // XML fileOffset
  uint64_t record_count = 0;             // XML recordCount
  std::vector<FieldCodec> fields;        // one per bytestream, prototype order
};

// Receives `count` decoded records: columns[f][i] is field f of record i,
// Integer as is, ScaledInteger already scaled. Called with count >= 1.
using RecordBatchFn =
    std::function<Status(size_t count, const std::vector<std::vector<double>>& columns)>;

// Streams a CompressedVector section packet by packet (memory: one packet
// plus the undecoded tail of each bytestream), calling `on_batch` with up to
// 65536 records at a time, in order. Errors name the file, the section's byte
// offset or the packet's, and the record index reached.
Status DecodeCompressedVector(PagedReader* file, const CompressedVectorSpec& spec,
                              const RecordBatchFn& on_batch);

}  // namespace pb::e57
