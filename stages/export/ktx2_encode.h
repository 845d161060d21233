// Basis Universal encoding of a baked map into a KTX2 file, for export.gltf's
// `textures: ktx2` (KHR_texture_basisu). The encoder is Basis Universal
// compiled to WebAssembly from npm (ktx2-encoder, pinned in
// tools/package-lock.json, installed by .ci/setup with `npm ci --prefix
// tools`), run by Node.js through tools/encode_ktx2.mjs in a child process:
// Debian 12 packages no Basis Universal encoder. The encoder is
// deterministic: the same image gives the same bytes.
//
// Two encoders, by the image's size: ktx2-encoder 0.6.0 (Basis Universal
// 2.5) up to kKtx2CurrentEncoderMaxTexels, its limit (a 4096² map is over
// it), and above that ktx2-encoder 0.5.4 (the previous WebAssembly, npm
// alias ktx2-encoder-legacy), which encodes 4096² maps (docs/export.md).
// Maps that 0.6.0 takes keep its bytes.
//
// Where the script is: $POINTBAKE_TOOLS_DIR, else the source tree's tools/
// (compiled in). `node` is looked up on PATH.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/image.h"

namespace pb {

// The most texels ktx2-encoder 0.6.0 encodes (12 Mi); larger images go to
// ktx2-encoder-legacy (EncodeKtx2 chooses, and tells tools/encode_ktx2.mjs).
inline constexpr int64_t kKtx2CurrentEncoderMaxTexels = int64_t{12} * 1024 * 1024;

enum class Ktx2Mode {
  kEtc1sSrgb,   // color maps: ETC1S (BasisLZ), sRGB, smallest on the GPU (ETC2 RGB, 4 bits/texel)
  kUastcLinear  // normal maps: UASTC 4x4 + Zstandard, linear (ASTC 4x4, 8 bits/texel), keeps
                // the detail ETC1S's shared endpoints blur in normals
};

// A KTX2 file with a full mip chain for `image` (8-bit, 1 to 4 channels: gray
// is repeated into RGB, a missing alpha is opaque; rows top first, as our
// PNGs). Status naming `what` and the encoder's message when Node.js, the
// script or its packages are missing or the encoding fails. `encoder`, when
// given, gets the encoder's "ktx2-encoder <version>" (Ktx2EncoderVersion).
Expected<std::vector<uint8_t>> EncodeKtx2(const Image& image, Ktx2Mode mode, const std::string& what,
                                          std::string* encoder = nullptr);

// "ktx2-encoder <version>" of the encoder that takes an image of `texels`
// texels (from its package.json), for the exported model's meta; "" when it
// is not installed.
std::string Ktx2EncoderVersion(int64_t texels = 1);

}  // namespace pb
