// LAZ: LAS with compressed point records (LASzip 2 and 3, the format of
// laszip, laz-perf and PDAL; COPC files are LAZ with a spatial ordering of
// the chunks and are read as LAZ). Spec: the LASzip format description (M.
// Isenburg, "LASzip: lossless compression of LiDAR data", PE&RS 79(2), 2013)
// and LASzip/design/specification.rst for the layered LAS 1.4 compressor;
// the codecs are in laz_codec.h, laz_items.h and laz_chunk_codec.h.
//
// Layout (after the LAS header and its VLRs, all little-endian):
//   laszip VLR (user id "laszip encoded", record id 22204), payload:
//      0 u16 compressor: 1 pointwise, 2 pointwise chunked, 3 layered chunked
//      2 u16 coder (0 = arithmetic)   4 u8 u8 u16 version (major minor rev)
//      8 u32 options   12 u32 chunk size in points (0xFFFFFFFF = variable,
//        the counts are in the chunk table)   16 i64 i64 (unused here)
//     32 u16 item count, then per item u16 type, u16 size, u16 version
//   at the point data offset: i64 offset of the chunk table (-1: it is in
//   the file's last 8 bytes), then the chunks; each chunk begins with its
//   first point's raw record, then (pointwise) one arithmetic-coded stream,
//   or (layered) u32 point count, u32 byte count per layer, the layers.
//   chunk table: u32 version (0), u32 chunk count, then arithmetic-coded
//   with an integer model (32 bits, 2 contexts): per chunk its point count
//   (variable chunk size only, context 0) and its byte count (context 1),
//   each predicted by the previous chunk's.
//
// Supported: point formats 0-3 (items POINT10, GPSTIME11, RGB12, BYTE, all
// version 2) and 6-8 (POINT14, RGB14, RGBNIR14, BYTE14, version 3), with
// extra bytes. Not: formats 4, 5, 9, 10 (waveforms), item version 1 (LASzip
// 1.x files), the non-arithmetic coder.
//
// Reading is streamed: a batch of chunks (at most 64 MiB of records) is
// read, decoded in parallel (TBB, one task per chunk), handed over, then the
// next. LAZ has no checksums: damage is found where it breaks the structure
// (chunk table, layer sizes, a stream that runs out or reaches an impossible
// coder state) and reported with the chunk, its bytes and the point, e.g.
//   scan.laz: LAZ chunk 3 of 8 (points 150000-199999, bytes 2210931-2947339):
//   compressed data ran out at point 170112
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "stages/geometry/core/buffered_input.h"
#include "stages/geometry/io/laz_chunk_codec.h"

namespace pb {

// What the LAS header says about the point records.
struct LazPointLayout {
  uint64_t point_offset = 0;  // the header's offset to point data
  uint64_t point_count = 0;
  int point_format = 0;     // without the compression bits
  size_t record_bytes = 0;  // the header's point record length
};

struct LazOptions {
  // false: decode only the layers the scan reader uses (XY, Z, intensity,
  // RGB); the other fields of the records then hold each chunk's first
  // point's values. true: every field (tests, decompression).
  bool all_layers = false;
  size_t max_batch_bytes = size_t{64} << 20;  // records decoded per batch
};

class LazReader {
 public:
  // `vlr` is the laszip VLR's payload, found at byte `vlr_offset`. Reads the
  // chunk table through `in` (which must outlive the reader).
  static Expected<std::unique_ptr<LazReader>> Open(BufferedInput* in, const std::string& path,
                                                   const LazPointLayout& layout,
                                                   std::span<const uint8_t> vlr,
                                                   uint64_t vlr_offset, const LazOptions& options);

  // The next points' records (layout.record_bytes each, in file order);
  // empty once every point was returned. Valid until the next call.
  Status Next(std::span<const uint8_t>* records);

  uint64_t chunk_count() const { return chunks_.size(); }
  // e.g. "laz layered" or "laz pointwise".
  std::string description() const;

 private:
  struct Chunk {
    uint64_t offset;  // file byte of the chunk's first byte
    uint64_t bytes;
    uint64_t first_point;
    uint64_t points;
  };

  LazReader(BufferedInput* in, const std::string& path, const LazPointLayout& layout,
            const LazOptions& options)
      : in_(in), path_(path), layout_(layout), options_(options) {}

  Status ParseVlr(std::span<const uint8_t> vlr, uint64_t vlr_offset);
  Status ReadChunkTable();
  std::string ChunkPlace(size_t chunk) const;
  Status DecodeChunk(size_t chunk, std::span<const uint8_t> bytes, uint8_t* records) const;

  BufferedInput* in_;
  std::string path_;
  LazPointLayout layout_;
  LazOptions options_;
  uint16_t compressor_ = 0;
  uint32_t chunk_size_ = 0;
  std::vector<laz::Item> items_;
  std::vector<bool> wanted_layers_;  // per layer of a layered chunk
  std::vector<Chunk> chunks_;
  size_t next_chunk_ = 0;
  std::vector<uint8_t> records_;
  std::vector<std::vector<uint8_t>> compressed_;
};

}  // namespace pb
