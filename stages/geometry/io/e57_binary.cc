// E57 pages and CompressedVector decoding; see e57_binary.h for the layout.
// Reference: ASTM E2807-11 "Standard Specification for 3D Imaging Data
// Exchange, Version 1.0", section 8 (binary file structure: pages, CRC-32C,
// physical/logical offsets) and section 9.5-9.7 (CompressedVector binary
// section, packets, bitPackCodec). Departure: index packets are never used
// (records are read from the first data packet on), so a file whose index is
// damaged still reads.
#include "stages/geometry/io/e57_binary.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <cstring>
#include <limits>

namespace pb::e57 {
namespace {

static_assert(std::endian::native == std::endian::little,
              "E57 decoding assumes a little-endian host");

constexpr std::array<uint32_t, 256> MakeCrcTable() {
  std::array<uint32_t, 256> table{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1) ? (c >> 1) ^ 0x82F63B78u : c >> 1;
    table[i] = c;
  }
  return table;
}
constexpr std::array<uint32_t, 256> kCrcTable = MakeCrcTable();

template <typename T>
T LoadLe(const uint8_t* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  return value;
}

}  // namespace

uint32_t Crc32c(const uint8_t* data, size_t size) {
  uint32_t crc = 0xFFFFFFFFu;
  for (size_t i = 0; i < size; ++i) crc = kCrcTable[(crc ^ data[i]) & 0xFF] ^ (crc >> 8);
  return crc ^ 0xFFFFFFFFu;
}

// ---------------------------------------------------------------------------
// PagedReader

PagedReader::~PagedReader() {
  if (fd_ >= 0) ::close(fd_);
}

Status PagedReader::Open(const std::string& path) {
  path_ = path;
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) return Status::Errno(path, "open");
  struct stat st;
  if (::fstat(fd_, &st) != 0) return Status::Errno(path, "stat");
  if (!S_ISREG(st.st_mode)) return Status::Invalid(path + ": not a regular file");
  file_bytes_ = static_cast<uint64_t>(st.st_size);
  return Status::Ok();
}

Status PagedReader::ReadRaw(size_t size, uint8_t* out) {
  size_t done = 0;
  while (done < size) {
    const ssize_t n = ::pread(fd_, out + done, size - done, static_cast<off_t>(done));
    if (n < 0) {
      if (errno == EINTR) continue;
      return Status::Errno(path_, "read");
    }
    if (n == 0) break;
    done += static_cast<size_t>(n);
  }
  if (done < size) {
    return Status::Corrupt(path_ + ": not an E57 file: " + std::to_string(done) +
                           " bytes, shorter than the 48-byte header");
  }
  return Status::Ok();
}

Status PagedReader::LoadPages(uint64_t first_page) {
  const uint64_t total_pages = file_bytes_ / kPageBytes;
  if (first_page >= total_pages) {
    return Status::Corrupt(path_ + ": truncated: page " + std::to_string(first_page) + " (byte " +
                           std::to_string(first_page * kPageBytes) + ") is past the end of the " +
                           std::to_string(file_bytes_) + "-byte file");
  }
  const uint64_t pages = std::min(kCachePages, total_pages - first_page);
  cache_.resize(pages * kPageBytes);
  cache_pages_ = 0;
  size_t done = 0;
  while (done < cache_.size()) {
    const ssize_t n = ::pread(fd_, cache_.data() + done, cache_.size() - done,
                              static_cast<off_t>(first_page * kPageBytes + done));
    if (n < 0) {
      if (errno == EINTR) continue;
      return Status::Errno(path_, "read");
    }
    if (n == 0) return Status::Corrupt(path_ + ": truncated while reading (file shrank?)");
    done += static_cast<size_t>(n);
  }
  bytes_loaded_ += done;
#ifndef PB_E57_FUZZ_SKIP_CRC
  for (uint64_t p = 0; p < pages; ++p) {
    const uint8_t* page = cache_.data() + p * kPageBytes;
    const uint32_t stored = static_cast<uint32_t>(page[1020]) << 24 |
                            static_cast<uint32_t>(page[1021]) << 16 |
                            static_cast<uint32_t>(page[1022]) << 8 | page[1023];
    if (Crc32c(page, kPageDataBytes) != stored) {
      const uint64_t index = first_page + p;
      return Status::Corrupt(path_ + ": CRC-32C mismatch in page " + std::to_string(index) +
                             " (byte " + std::to_string(index * kPageBytes) + ")");
    }
  }
#endif
  cache_first_page_ = first_page;
  cache_pages_ = pages;
  return Status::Ok();
}

Status PagedReader::Read(uint64_t logical, size_t size, uint8_t* out) {
  while (size > 0) {
    const uint64_t page = logical / kPageDataBytes;
    const uint64_t in_page = logical % kPageDataBytes;
    if (page < cache_first_page_ || page >= cache_first_page_ + cache_pages_) {
      PB_RETURN_IF_ERROR(LoadPages(page));
    }
    const size_t n = static_cast<size_t>(std::min<uint64_t>(size, kPageDataBytes - in_page));
    std::memcpy(out, cache_.data() + (page - cache_first_page_) * kPageBytes + in_page, n);
    out += n;
    size -= n;
    logical += n;
  }
  return Status::Ok();
}

// ---------------------------------------------------------------------------
// CompressedVector

int FieldCodec::BitsPerValue() const {
  switch (kind) {
    case Kind::kFloat32:
      return 32;
    case Kind::kFloat64:
      return 64;
    case Kind::kInteger:
    case Kind::kScaledInteger: {
      const uint64_t range = static_cast<uint64_t>(maximum) - static_cast<uint64_t>(minimum);
      return std::bit_width(range);
    }
  }
  return 0;
}

namespace {

// One field's bytestream: bytes received and not yet fully consumed.
class BitStream {
 public:
  void Append(const uint8_t* data, size_t size) {
    // Drop consumed whole bytes first so the buffer stays about one packet.
    const size_t consumed = bit_pos_ / 8;
    if (consumed > 0) {
      bytes_.erase(bytes_.begin(), bytes_.begin() + static_cast<ptrdiff_t>(consumed));
      bit_pos_ -= consumed * 8;
    }
    bytes_.insert(bytes_.end(), data, data + size);
  }
  uint64_t AvailableBits() const { return bytes_.size() * 8 - bit_pos_; }

  // Next `bits` (1..64) bits, least significant first. Caller checked AvailableBits.
  uint64_t Take(int bits) {
    uint64_t result = 0;
    int got = 0;
    while (got < bits) {
      const size_t byte = static_cast<size_t>(bit_pos_ >> 3);
      const int shift = static_cast<int>(bit_pos_ & 7);
      const int take = std::min(8 - shift, bits - got);
      const uint64_t chunk = (static_cast<uint64_t>(bytes_[byte]) >> shift) & ((1u << take) - 1);
      result |= chunk << got;
      got += take;
      bit_pos_ += static_cast<uint64_t>(take);
    }
    return result;
  }
  // Next `size` whole bytes (float fields are byte aligned).
  const uint8_t* TakeBytes(size_t size) {
    const uint8_t* p = bytes_.data() + bit_pos_ / 8;
    bit_pos_ += size * 8;
    return p;
  }

 private:
  std::vector<uint8_t> bytes_;
  uint64_t bit_pos_ = 0;
};

constexpr size_t kMaxBatchRecords = 65536;

}  // namespace

Status DecodeCompressedVector(PagedReader* file, const CompressedVectorSpec& spec,
                              const RecordBatchFn& on_batch) {
  const std::string where = file->path() + ": " + spec.name;
  uint64_t section_start = 0;
  if (!PhysicalToLogical(spec.section_physical_offset, &section_start) ||
      section_start + 32 > file->logical_bytes()) {
    return Status::Corrupt(where + ": fileOffset " + std::to_string(spec.section_physical_offset) +
                           " is not a valid offset in the " + std::to_string(file->file_bytes()) +
                           "-byte file");
  }
  uint8_t header[32];
  PB_RETURN_IF_ERROR(file->Read(section_start, sizeof(header), header));
  const std::string section_at =
      " (section at byte " + std::to_string(spec.section_physical_offset) + ")";
  if (header[0] != 1) {
    return Status::Corrupt(where + ": expected a CompressedVector section (id 1), found id " +
                           std::to_string(header[0]) + section_at);
  }
  const uint64_t section_length = LoadLe<uint64_t>(header + 8);
  const uint64_t data_physical = LoadLe<uint64_t>(header + 16);
  if (section_length < 32 || section_length > file->logical_bytes() - section_start) {
    return Status::Corrupt(where + ": section length " + std::to_string(section_length) +
                           " does not fit in the file" + section_at);
  }
  const uint64_t section_end = section_start + section_length;

  const size_t field_count = spec.fields.size();
  uint64_t bits_per_record = 0;
  for (const FieldCodec& field : spec.fields) bits_per_record += field.BitsPerValue();
  if (spec.record_count > 0) {
    if (bits_per_record == 0) {
      return Status::Unsupported(where + ": every field is constant (0 bits per record)");
    }
    // Every record needs its bits inside the section: bounds what a forged
    // recordCount can make us do.
    if (spec.record_count > (section_length * 8) / bits_per_record) {
      return Status::Corrupt(where + ": recordCount " + std::to_string(spec.record_count) +
                             " cannot fit in a " + std::to_string(section_length) +
                             "-byte section" + section_at);
    }
  } else {
    return Status::Ok();
  }

  uint64_t packet = 0;
  if (!PhysicalToLogical(data_physical, &packet) || packet < section_start + 32 ||
      packet >= section_end) {
    return Status::Corrupt(where + ": dataPhysicalOffset " + std::to_string(data_physical) +
                           " lies outside the section" + section_at);
  }

  std::vector<BitStream> streams(field_count);
  std::vector<int> bits(field_count);
  for (size_t f = 0; f < field_count; ++f) bits[f] = spec.fields[f].BitsPerValue();
  std::vector<std::vector<double>> columns(field_count);
  std::vector<uint8_t> buffer;
  uint64_t records_done = 0;

  while (records_done < spec.record_count) {
    const std::string packet_at = " (packet at byte " + std::to_string(LogicalToPhysical(packet)) +
                                  ", record " + std::to_string(records_done) + " of " +
                                  std::to_string(spec.record_count) + ")";
    if (packet + 4 > section_end) {
      return Status::Corrupt(where + ": section ends after " + std::to_string(records_done) +
                             " of " + std::to_string(spec.record_count) + " records" + section_at);
    }
    uint8_t prefix[6];
    PB_RETURN_IF_ERROR(file->Read(packet, 4, prefix));
    const uint8_t type = prefix[0];
    const uint64_t packet_length = uint64_t{LoadLe<uint16_t>(prefix + 2)} + 1;
    if (packet + packet_length > section_end) {
      return Status::Corrupt(where + ": packet of " + std::to_string(packet_length) +
                             " bytes runs past the end of the section" + packet_at);
    }
    if (type == 0 || type == 2) {  // index or empty packet
      packet += packet_length;
      continue;
    }
    if (type != 1) {
      return Status::Corrupt(where + ": unknown packet type " + std::to_string(type) + packet_at);
    }
    if (packet_length < 6) {
      return Status::Corrupt(where + ": data packet of " + std::to_string(packet_length) +
                             " bytes is shorter than its header" + packet_at);
    }
    buffer.resize(packet_length);
    PB_RETURN_IF_ERROR(file->Read(packet, buffer.size(), buffer.data()));
    const uint16_t stream_count = LoadLe<uint16_t>(buffer.data() + 4);
    if (stream_count != field_count) {
      return Status::Corrupt(where + ": data packet has " + std::to_string(stream_count) +
                             " bytestreams, the prototype has " + std::to_string(field_count) +
                             " fields" + packet_at);
    }
    size_t cursor = 6 + 2 * field_count;
    if (cursor > packet_length) {
      return Status::Corrupt(where + ": data packet too short for its buffer lengths" + packet_at);
    }
    for (size_t f = 0; f < field_count; ++f) {
      const size_t length = LoadLe<uint16_t>(buffer.data() + 6 + 2 * f);
      if (cursor + length > packet_length) {
        return Status::Corrupt(where + ": bytestream " + std::to_string(f) + " buffer of " +
                               std::to_string(length) + " bytes overruns the packet" + packet_at);
      }
      streams[f].Append(buffer.data() + cursor, length);
      cursor += length;
    }
    packet += packet_length;

    // Decode every record all streams now hold, in lockstep.
    while (records_done < spec.record_count) {
      uint64_t ready = spec.record_count - records_done;
      for (size_t f = 0; f < field_count; ++f) {
        if (bits[f] > 0) ready = std::min<uint64_t>(ready, streams[f].AvailableBits() / bits[f]);
      }
      if (ready == 0) break;
      const size_t count = static_cast<size_t>(std::min<uint64_t>(ready, kMaxBatchRecords));
      for (size_t f = 0; f < field_count; ++f) {
        const FieldCodec& codec = spec.fields[f];
        std::vector<double>& column = columns[f];
        column.resize(count);
        BitStream& stream = streams[f];
        switch (codec.kind) {
          case FieldCodec::Kind::kFloat32:
            for (size_t i = 0; i < count; ++i) column[i] = LoadLe<float>(stream.TakeBytes(4));
            break;
          case FieldCodec::Kind::kFloat64:
            for (size_t i = 0; i < count; ++i) column[i] = LoadLe<double>(stream.TakeBytes(8));
            break;
          case FieldCodec::Kind::kInteger:
          case FieldCodec::Kind::kScaledInteger: {
            const uint64_t range =
                static_cast<uint64_t>(codec.maximum) - static_cast<uint64_t>(codec.minimum);
            const bool scaled = codec.kind == FieldCodec::Kind::kScaledInteger;
            for (size_t i = 0; i < count; ++i) {
              const uint64_t packed = bits[f] > 0 ? stream.Take(bits[f]) : 0;
              if (packed > range) {
                return Status::Corrupt(where + ": field " + std::to_string(f) + " of record " +
                                       std::to_string(records_done + i) +
                                       " is outside its [minimum, maximum]");
              }
              const auto raw = static_cast<int64_t>(static_cast<uint64_t>(codec.minimum) + packed);
              column[i] = scaled ? static_cast<double>(raw) * codec.scale + codec.offset
                                 : static_cast<double>(raw);
            }
            break;
          }
        }
      }
      PB_RETURN_IF_ERROR(on_batch(count, columns));
      records_done += count;
    }
  }
  return Status::Ok();
}

}  // namespace pb::e57
