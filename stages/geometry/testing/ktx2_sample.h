// For tests only: a minimal well-formed KTX 2.0 file (header, level index,
// a basic data format descriptor; level data zero-filled, not decodable) with
// the given Basis Universal codec (colorModel 163 ETC1S or 166 UASTC), size
// and number of mip levels.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

namespace pb::testing {

inline std::vector<uint8_t> Ktx2Sample(uint8_t color_model, uint32_t width, uint32_t height,
                                       uint32_t levels, bool srgb, int samples = 1) {
  auto put32 = [](std::vector<uint8_t>& b, size_t at, uint32_t v) { std::memcpy(&b[at], &v, 4); };
  auto put64 = [](std::vector<uint8_t>& b, size_t at, uint64_t v) { std::memcpy(&b[at], &v, 8); };
  const uint8_t id[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n'};
  const size_t index_end = 80 + 24 * size_t(levels);
  const uint32_t block = 24 + 16 * uint32_t(samples);
  const size_t dfd_offset = index_end, dfd_length = 4 + block;
  const size_t level_bytes = 16;
  std::vector<uint8_t> b(dfd_offset + dfd_length + levels * level_bytes, 0);
  std::memcpy(b.data(), id, 12);
  put32(b, 20, width);
  put32(b, 24, height);
  put32(b, 32, 0);
  put32(b, 36, 1);
  put32(b, 40, levels);
  put32(b, 44, color_model == 163 ? 1 : 2);
  put32(b, 48, uint32_t(dfd_offset));
  put32(b, 52, uint32_t(dfd_length));
  for (uint32_t level = 0; level < levels; ++level) {
    put64(b, 80 + 24 * level, dfd_offset + dfd_length + level * level_bytes);
    put64(b, 80 + 24 * level + 8, level_bytes);
  }
  put32(b, dfd_offset, uint32_t(dfd_length));
  put32(b, dfd_offset + 8, (block << 16) | 2);  // versionNumber 2, descriptorBlockSize
  b[dfd_offset + 12] = color_model;
  b[dfd_offset + 13] = 1;                // BT.709 primaries
  b[dfd_offset + 14] = srgb ? 2 : 1;     // transfer function
  return b;
}

}  // namespace pb::testing
