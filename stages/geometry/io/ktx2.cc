#include "stages/geometry/io/ktx2.h"

#include <algorithm>
#include <cstring>

namespace pb {
namespace {

constexpr uint8_t kIdentifier[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n'};
constexpr size_t kHeaderBytes = 80;  // identifier, header, index
constexpr size_t kLevelEntryBytes = 24;

uint32_t U32(std::span<const uint8_t> b, size_t at) {
  uint32_t v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}
uint64_t U64(std::span<const uint8_t> b, size_t at) {
  uint64_t v;
  std::memcpy(&v, b.data() + at, 8);
  return v;
}

}  // namespace

bool IsKtx2(std::span<const uint8_t> bytes) {
  return bytes.size() >= sizeof(kIdentifier) && std::memcmp(bytes.data(), kIdentifier, sizeof(kIdentifier)) == 0;
}

Expected<Ktx2Info> ReadKtx2Info(std::span<const uint8_t> bytes, const std::string& source) {
  auto corrupt = [&](const std::string& what) { return Status::Corrupt(source + ": KTX2: " + what); };
  if (!IsKtx2(bytes)) return corrupt("no KTX 2.0 identifier");
  if (bytes.size() < kHeaderBytes) return corrupt("header truncated");
  Ktx2Info info;
  info.vk_format = U32(bytes, 12);
  info.width = int(std::min<uint32_t>(U32(bytes, 20), 1u << 30));
  info.height = int(std::min<uint32_t>(U32(bytes, 24), 1u << 30));
  info.levels = int(std::max<uint32_t>(1, std::min<uint32_t>(U32(bytes, 40), 32)));
  info.supercompression = U32(bytes, 44);
  if (info.width <= 0) return corrupt("pixelWidth is 0");
  if (U32(bytes, 28) > 1 || U32(bytes, 32) > 1 || U32(bytes, 36) > 1) {
    return corrupt("not a 2-D texture (depth, layers or faces)");
  }
  if (uint64_t(kHeaderBytes) + uint64_t(info.levels) * kLevelEntryBytes > bytes.size()) {
    return corrupt("level index truncated");
  }
  for (int level = 0; level < info.levels; ++level) {
    const size_t entry = kHeaderBytes + size_t(level) * kLevelEntryBytes;
    const uint64_t offset = U64(bytes, entry), length = U64(bytes, entry + 8);
    if (offset > bytes.size() || length > bytes.size() - offset) {
      return corrupt("level " + std::to_string(level) + " ends past the file");
    }
    info.data_bytes += length;
  }
  const uint64_t dfd_offset = U32(bytes, 48), dfd_length = U32(bytes, 52);
  // dfdTotalSize (4), then the basic block: vendor/type (4), version/size
  // (4), colorModel, colorPrimaries, transferFunction, flags, texel block
  // dimensions (4), bytesPlane (8), samples of 16 bytes each.
  if (dfd_length < 28 || dfd_offset > bytes.size() || dfd_length > bytes.size() - dfd_offset) {
    return corrupt("data format descriptor missing or past the file");
  }
  const uint8_t color_model = bytes[dfd_offset + 12];
  info.srgb = bytes[dfd_offset + 14] == 2;
  const uint32_t block_size = U32(bytes, dfd_offset + 8) >> 16;
  const int samples = block_size >= 24 ? int((block_size - 24) / 16) : 0;
  info.codec = color_model == 163 ? Ktx2Codec::kEtc1s : color_model == 166 ? Ktx2Codec::kUastc : Ktx2Codec::kOther;
  info.has_alpha = info.codec == Ktx2Codec::kEtc1s && samples >= 2;
  if (info.codec != Ktx2Codec::kOther && info.vk_format != 0) {
    return corrupt("Basis Universal data with vkFormat " + std::to_string(info.vk_format) + " (expected 0)");
  }
  return info;
}

uint64_t Ktx2GpuBytes(const Ktx2Info& info) {
  uint64_t block_bytes = 0;
  if (info.codec == Ktx2Codec::kEtc1s) block_bytes = info.has_alpha ? 16 : 8;
  if (info.codec == Ktx2Codec::kUastc) block_bytes = 16;
  uint64_t total = 0;
  uint64_t w = uint64_t(info.width), h = uint64_t(std::max(info.height, 1));
  for (int level = 0; level < info.levels; ++level) {
    total += ((w + 3) / 4) * ((h + 3) / 4) * block_bytes;
    w = std::max<uint64_t>(1, w / 2);
    h = std::max<uint64_t>(1, h / 2);
  }
  return total;
}

}  // namespace pb
