// LAZ test support, for tests and benchmarks only: synthetic airborne LAS
// files, and a LAZ writer: the arithmetic encoder that
// mirrors laz::ArithmeticDecoder (Said 2003, as LAZ uses it) and
// CompressLas, which turns an uncompressed LAS file's bytes into LAZ with
// the item codecs of laz_items.h in encoding mode. The reader does not need
// it; the tests round-trip through it and check its files with the npm
// laz-perf decoder, which shares no code with ours.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "stages/geometry/io/laz_codec.h"

namespace pb::laz {

class ArithmeticEncoder {
 public:
  void EncodeBit(BitModel& m, uint32_t bit);
  void EncodeSymbol(SymbolModel& m, uint32_t symbol);
  void WriteBits(uint32_t bits, uint32_t value);
  void WriteInt(uint32_t value);
  void EncodeInt(IntegerModel& ic, int32_t prediction, int32_t real, uint32_t context);
  // Flushes and returns the stream; the encoder is then empty again.
  std::vector<uint8_t> Done();

 private:
  void PropagateCarry();
  void Renormalize();

  std::vector<uint8_t> out_;
  uint32_t base_ = 0;
  uint32_t length_ = kMaxLength;
};

// The encoding side of the coder interface (see laz::DecodingCoder).
class EncodingCoder {
 public:
  static constexpr bool kEncoding = true;

  void Init(const uint8_t*, const uint8_t*) {}
  uint32_t Bit(BitModel& m, uint32_t bit) {
    encoder_.EncodeBit(m, bit);
    return bit;
  }
  uint32_t Symbol(SymbolModel& m, uint32_t symbol) {
    encoder_.EncodeSymbol(m, symbol);
    return symbol;
  }
  uint32_t Raw32(uint32_t value) {
    encoder_.WriteInt(value);
    return value;
  }
  int32_t Int(IntegerModel& ic, int32_t prediction, int32_t real, uint32_t context) {
    encoder_.EncodeInt(ic, prediction, real, context);
    return real;
  }
  std::vector<uint8_t> Done() { return encoder_.Done(); }

 private:
  ArithmeticEncoder encoder_;
};

struct LazWriteOptions {
  uint32_t chunk_size = 50000;  // points per chunk
  // Non-empty: variable chunks of these point counts (summing to the
  // file's), chunk size 0xFFFFFFFF in the VLR, as COPC writes.
  std::vector<uint32_t> chunk_points;
  bool table_offset_at_end = false;  // -1 at the point data, as streaming writers do
  // Compressor 1: one pointwise stream, no chunks, no chunk table (formats
  // 0-3 only), as the first LASzip versions wrote.
  bool not_chunked = false;
  // COPC layout: the "copc" info VLR first, variable chunks as octree
  // nodes listed in a hierarchy EVLR. Needs LAS 1.4 and format 6-8.
  bool copc = false;
};

// `las` is an uncompressed LAS 1.0-1.4 file (formats 0-3, 6-8); returns the
// same file compressed. Aborts (assert) on input it was not written for.
std::string CompressLas(const std::string& las, const LazWriteOptions& options = {});

// An uncompressed LAS file (LAS 1.2 for formats 0-3, 1.4 for 6-8) whose
// every field varies the way airborne scans do: pulses of 1-3 returns (up
// to 7 or 15 now and then), two interleaved flight lines (GPS time jumps
// between sequences), up to `scanner_channels` channels switching (formats
// 6-8), grey and colored points, `extra_bytes` extra bytes per record.
std::string SyntheticAirborneLas(int format, size_t points, size_t extra_bytes = 0,
                                 uint32_t seed = 1, int scanner_channels = 4);

}  // namespace pb::laz
