// KTX 2.0 texture containers (Khronos KTX File Format Specification 2.0):
// what pointbake needs to know of the Basis Universal maps it embeds in a
// .glb (KHR_texture_basisu) — their size, mip levels and codec — and the GPU
// memory they take once transcoded. Encoding is not done here (the export
// stage runs an encoder; stages/export/ktx2_encode.h).
//
// Read from the file (little-endian): the 12-byte identifier
// «KTX 20»\r\n\x1A\n, vkFormat (0 for Basis Universal), pixelWidth,
// pixelHeight, levelCount, supercompressionScheme (1 = BasisLZ, used by
// ETC1S; 2 = Zstandard), the level index (per level: offset, length within
// the file) and the data format descriptor's colorModel (163 = ETC1S,
// 166 = UASTC), transferFunction (2 = sRGB) and sample count (channels as
// coded: ETC1S with 2 samples has an alpha slice).
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "base/status.h"

namespace pb {

enum class Ktx2Codec { kOther, kEtc1s, kUastc };

struct Ktx2Info {
  uint32_t vk_format = 0;
  int width = 0;
  int height = 0;
  int levels = 0;                  // mip levels stored (levelCount 0 is read as 1)
  uint32_t supercompression = 0;
  Ktx2Codec codec = Ktx2Codec::kOther;
  bool srgb = false;               // transferFunction sRGB
  bool has_alpha = false;          // ETC1S: a second (alpha) slice
  uint64_t data_bytes = 0;         // sum of the stored levels' lengths
};

// Checks the identifier, the header, the level index (every level inside
// the file) and the descriptor; Status::Corrupt naming `source` and what is
// wrong otherwise.
Expected<Ktx2Info> ReadKtx2Info(std::span<const uint8_t> bytes, const std::string& source);

// True when `bytes` starts with the KTX 2.0 identifier.
bool IsKtx2(std::span<const uint8_t> bytes);

// GPU memory of the texture once a mobile GPU's loader transcodes it, bytes,
// over the stored levels: ETC1S to ETC2 (8 bytes per 4x4 block; 16 with
// alpha), UASTC to ASTC 4x4 (16 bytes per block). The usual targets of
// three.js's and Unity's KTX2 loaders on Adreno and Mali GPUs; desktop GPUs
// transcode to BC1/BC7 of the same sizes. 0 for other codecs.
uint64_t Ktx2GpuBytes(const Ktx2Info& info);

}  // namespace pb
