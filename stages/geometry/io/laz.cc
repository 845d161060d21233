#include "stages/geometry/io/laz.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstring>

namespace pb {
namespace {

using laz::Item;

constexpr uint32_t kVariableChunkSize = 0xFFFFFFFFu;
// A valid stream is never read past its end; a little slack for writers
// whose final flush is short.
constexpr size_t kMaxOverrunBytes = 4;

std::string ItemName(uint16_t type) {
  switch (type) {
    case Item::kByte:
      return "BYTE";
    case Item::kPoint10:
      return "POINT10";
    case Item::kGpsTime11:
      return "GPSTIME11";
    case Item::kRgb12:
      return "RGB12";
    case 9:
      return "WAVEPACKET13";
    case Item::kPoint14:
      return "POINT14";
    case Item::kRgb14:
      return "RGB14";
    case Item::kRgbNir14:
      return "RGBNIR14";
    case 13:
      return "WAVEPACKET14";
    case Item::kByte14:
      return "BYTE14";
    default:
      return "type " + std::to_string(type);
  }
}

// The items a point format is made of, as LASzip writes them.
std::vector<uint16_t> ExpectedItems(int format) {
  switch (format) {
    case 0:
      return {Item::kPoint10};
    case 1:
      return {Item::kPoint10, Item::kGpsTime11};
    case 2:
      return {Item::kPoint10, Item::kRgb12};
    case 3:
      return {Item::kPoint10, Item::kGpsTime11, Item::kRgb12};
    case 6:
      return {Item::kPoint14};
    case 7:
      return {Item::kPoint14, Item::kRgb14};
    case 8:
      return {Item::kPoint14, Item::kRgbNir14};
    default:
      return {};
  }
}

uint16_t ItemSize(uint16_t type) {
  switch (type) {
    case Item::kPoint10:
      return 20;
    case Item::kGpsTime11:
      return 8;
    case Item::kRgb12:
      return 6;
    case Item::kPoint14:
      return 30;
    case Item::kRgb14:
      return 6;
    case Item::kRgbNir14:
      return 8;
    default:
      return 0;
  }
}

}  // namespace

Expected<std::unique_ptr<LazReader>> LazReader::Open(BufferedInput* in, const std::string& path,
                                                     const LazPointLayout& layout,
                                                     std::span<const uint8_t> vlr,
                                                     uint64_t vlr_offset,
                                                     const LazOptions& options) {
  std::unique_ptr<LazReader> reader(new LazReader(in, path, layout, options));
  PB_RETURN_IF_ERROR(reader->ParseVlr(vlr, vlr_offset));
  PB_RETURN_IF_ERROR(reader->ReadChunkTable());
  return reader;
}

std::string LazReader::description() const {
  return compressor_ == 3 ? "laz layered" : "laz pointwise";
}

Status LazReader::ParseVlr(std::span<const uint8_t> vlr, uint64_t vlr_offset) {
  const std::string where = " (laszip VLR at byte " + std::to_string(vlr_offset) + ")";
  if (vlr.size() < 34) {
    return Status::Corrupt(path_ + ": laszip VLR of " + std::to_string(vlr.size()) +
                           " bytes is shorter than its 34-byte fixed part" + where);
  }
  compressor_ = laz::LoadLe<uint16_t>(vlr.data());
  const uint16_t coder = laz::LoadLe<uint16_t>(vlr.data() + 2);
  chunk_size_ = laz::LoadLe<uint32_t>(vlr.data() + 12);
  const uint16_t item_count = laz::LoadLe<uint16_t>(vlr.data() + 32);
  if (compressor_ < 1 || compressor_ > 3) {
    return Status::Unsupported(
        path_ + ": LAZ compressor " + std::to_string(compressor_) +
        " is unknown (expected 1 pointwise, 2 pointwise chunked or 3 layered)" + where);
  }
  if (coder != 0) {
    return Status::Unsupported(path_ + ": LAZ coder " + std::to_string(coder) +
                               " is unknown (only 0, arithmetic, exists)" + where);
  }
  if (chunk_size_ == 0 && compressor_ != 1)
    return Status::Corrupt(path_ + ": LAZ chunk size 0" + where);
  if (vlr.size() < 34 + 6 * size_t{item_count}) {
    return Status::Corrupt(path_ + ": laszip VLR lists " + std::to_string(item_count) +
                           " items but has room for " + std::to_string((vlr.size() - 34) / 6) +
                           where);
  }
  const int format = layout_.point_format;
  const std::vector<uint16_t> expected = ExpectedItems(format);
  if (expected.empty()) {
    return Status::Unsupported(path_ + ": LAZ point format " + std::to_string(format) +
                               " (waveforms) is not supported; formats 0-3 and 6-8 are");
  }
  const bool layered = format >= 6;
  if (layered != (compressor_ == 3)) {
    return Status::Corrupt(path_ + ": LAZ compressor " + std::to_string(compressor_) +
                           " does not fit point format " + std::to_string(format) +
                           " (formats 6-10 are layered, 3; formats 0-5 pointwise, 1 or 2)" + where);
  }
  size_t bytes = 0;
  for (uint16_t i = 0; i < item_count; ++i) {
    const uint8_t* entry = vlr.data() + 34 + 6 * i;
    Item item{laz::LoadLe<uint16_t>(entry), laz::LoadLe<uint16_t>(entry + 2),
              laz::LoadLe<uint16_t>(entry + 4)};
    const std::string name = "item " + std::to_string(i) + " (" + ItemName(item.type) + ")";
    const bool is_extra = item.type == Item::kByte || item.type == Item::kByte14;
    const bool in_format = i < expected.size() && item.type == expected[i];
    const bool extra_ok = i == expected.size() && i + 1 == item_count &&
                          item.type == (layered ? Item::kByte14 : Item::kByte) && item.size > 0;
    if (!in_format && !extra_ok) {
      return Status::Corrupt(path_ + ": laszip VLR " + name + " does not belong to point format " +
                             std::to_string(format) + where);
    }
    if (!is_extra && item.size != ItemSize(item.type)) {
      return Status::Corrupt(path_ + ": laszip VLR " + name + " has size " +
                             std::to_string(item.size) + ", expected " +
                             std::to_string(ItemSize(item.type)) + where);
    }
    const uint16_t version = layered ? 3 : 2;
    if (item.version != version) {
      return Status::Unsupported(path_ + ": laszip VLR " + name + " version " +
                                 std::to_string(item.version) + " is not supported (expected " +
                                 std::to_string(version) + ")" + where);
    }
    bytes += item.size;
    items_.push_back(item);
  }
  if (items_.size() < expected.size() || bytes != layout_.record_bytes) {
    return Status::Corrupt(path_ + ": laszip VLR items cover " + std::to_string(bytes) +
                           " bytes, the header's point record length (byte 105) is " +
                           std::to_string(layout_.record_bytes) + where);
  }
  // Layers the scan reader needs: XY, Z, intensity, RGB.
  if (layered) {
    wanted_layers_.assign(laz::Point14Codec<laz::DecodingCoder>::kLayers, options_.all_layers);
    wanted_layers_[laz::Point14Codec<laz::DecodingCoder>::kXY] = true;
    wanted_layers_[laz::Point14Codec<laz::DecodingCoder>::kZ] = true;
    wanted_layers_[laz::Point14Codec<laz::DecodingCoder>::kIntensity] = true;
    for (const Item& item : items_) {
      if (item.type == Item::kRgb14) wanted_layers_.push_back(true);
      if (item.type == Item::kRgbNir14) {
        wanted_layers_.push_back(true);
        wanted_layers_.push_back(options_.all_layers);
      }
      if (item.type == Item::kByte14)
        wanted_layers_.resize(wanted_layers_.size() + item.size, options_.all_layers);
    }
  }
  return Status::Ok();
}

Status LazReader::ReadChunkTable() {
  const uint64_t file_bytes = in_->size();
  const uint64_t count = layout_.point_count;
  if (count == 0) return Status::Ok();
  auto corrupt = [&](const std::string& what) { return Status::Corrupt(path_ + ": " + what); };
  if (compressor_ == 1) {  // not chunked: one stream from the point data to the end
    const uint64_t start = layout_.point_offset;
    if (start + layout_.record_bytes > file_bytes) {
      return corrupt("truncated: LAZ point data at byte " + std::to_string(start) + " (file has " +
                     std::to_string(file_bytes) + " bytes)");
    }
    chunks_.push_back({start, file_bytes - start, 0, count});
    return Status::Ok();
  }
  uint8_t word[8];
  if (!in_->Seek(layout_.point_offset) || !in_->Read(word, 8)) {
    PB_RETURN_IF_ERROR(in_->error());
    return corrupt("truncated: no LAZ chunk table offset at byte " +
                   std::to_string(layout_.point_offset) + " (file has " +
                   std::to_string(file_bytes) + " bytes)");
  }
  int64_t table_offset = laz::LoadLe<int64_t>(word);
  uint64_t table_offset_at = layout_.point_offset;
  if (table_offset == -1) {  // written by a streaming writer: in the last 8 bytes
    table_offset_at = file_bytes - 8;
    if (file_bytes < 8 || !in_->Seek(table_offset_at) || !in_->Read(word, 8)) {
      PB_RETURN_IF_ERROR(in_->error());
      return corrupt("truncated: no LAZ chunk table offset at the end of the file");
    }
    table_offset = laz::LoadLe<int64_t>(word);
  }
  const uint64_t first_chunk = layout_.point_offset + 8;
  if (table_offset < static_cast<int64_t>(first_chunk) ||
      static_cast<uint64_t>(table_offset) + 8 > file_bytes) {
    return corrupt("LAZ chunk table offset " + std::to_string(table_offset) + " (byte " +
                   std::to_string(table_offset_at) + ") is outside the file's " +
                   std::to_string(first_chunk) + ".." + std::to_string(file_bytes) +
                   " bytes; truncated file?");
  }
  uint8_t head[8];
  if (!in_->Seek(table_offset) || !in_->Read(head, 8)) {
    PB_RETURN_IF_ERROR(in_->error());
    return corrupt("truncated LAZ chunk table at byte " + std::to_string(table_offset));
  }
  const uint32_t version = laz::LoadLe<uint32_t>(head);
  const uint32_t chunk_count = laz::LoadLe<uint32_t>(head + 4);
  const std::string table = "LAZ chunk table at byte " + std::to_string(table_offset);
  if (version != 0) return corrupt(table + ": version " + std::to_string(version) + ", expected 0");
  if (chunk_count == 0 || chunk_count > count) {
    return corrupt(table + ": " + std::to_string(chunk_count) + " chunks for " +
                   std::to_string(count) + " points");
  }
  // Each entry takes a few bytes; never read more than the file has.
  const uint64_t table_bytes =
      std::min<uint64_t>(file_bytes - table_offset - 8, 64 + uint64_t{chunk_count} * 24);
  std::vector<uint8_t> coded(table_bytes);
  if (!in_->Read(coded.data(), coded.size())) {
    PB_RETURN_IF_ERROR(in_->error());
    return corrupt("truncated " + table);
  }
  laz::ArithmeticDecoder decoder;
  decoder.Init(coded.data(), coded.data() + coded.size());
  laz::IntegerModel ic(32, 2);
  const bool variable = chunk_size_ == kVariableChunkSize;
  uint64_t offset = first_chunk, first_point = 0;
  int32_t last_points = 0, last_bytes = 0;
  chunks_.reserve(chunk_count);
  for (uint32_t i = 0; i < chunk_count; ++i) {
    uint64_t points;
    if (variable) {
      last_points = decoder.DecodeInt(ic, last_points, 0);
      points = static_cast<uint32_t>(last_points);
    } else {
      points = std::min<uint64_t>(chunk_size_, count - std::min(count, first_point));
    }
    last_bytes = decoder.DecodeInt(ic, last_bytes, 1);
    const uint64_t bytes = static_cast<uint32_t>(last_bytes);
    if (decoder.overrun_bytes() > kMaxOverrunBytes || decoder.corrupt()) {
      return corrupt(table + ": damaged at entry " + std::to_string(i));
    }
    if (points == 0 || bytes < layout_.record_bytes ||
        offset + bytes > static_cast<uint64_t>(table_offset)) {
      return corrupt(table + ": chunk " + std::to_string(i) + " (" + std::to_string(points) +
                     " points, " + std::to_string(bytes) + " bytes from byte " +
                     std::to_string(offset) + ") does not fit before the table");
    }
    chunks_.push_back({offset, bytes, first_point, points});
    offset += bytes;
    first_point += points;
  }
  if (first_point != count) {
    return corrupt(table + ": the chunks hold " + std::to_string(first_point) +
                   " points, the header says " + std::to_string(count));
  }
  return Status::Ok();
}

std::string LazReader::ChunkPlace(size_t chunk) const {
  const Chunk& c = chunks_[chunk];
  return path_ + ": LAZ chunk " + std::to_string(chunk) + " of " + std::to_string(chunks_.size()) +
         " (points " + std::to_string(c.first_point) + "-" +
         std::to_string(c.first_point + c.points - 1) + ", bytes " + std::to_string(c.offset) +
         "-" + std::to_string(c.offset + c.bytes - 1) + ")";
}

Status LazReader::DecodeChunk(size_t chunk, std::span<const uint8_t> bytes,
                              uint8_t* records) const {
  const Chunk& c = chunks_[chunk];
  const size_t record_bytes = layout_.record_bytes;
  std::memcpy(records, bytes.data(), record_bytes);  // the first point is raw
  if (c.points == 1) return Status::Ok();
  laz::ChunkCodec<laz::DecodingCoder> codec(items_, records);
  const uint8_t* next = bytes.data() + record_bytes;
  const uint8_t* end = bytes.data() + bytes.size();
  std::vector<laz::DecodingCoder*> active;
  if (!codec.layered()) {
    codec.stream().Init(next, end);
    active.push_back(&codec.stream());
  } else {
    const size_t layers = codec.layers().size();
    if (static_cast<size_t>(end - next) < 4 + 4 * layers) {
      return Status::Corrupt(ChunkPlace(chunk) + ": too short for its " + std::to_string(layers) +
                             " layer sizes");
    }
    next += 4;  // the point count, known from the chunk table
    const uint8_t* sizes = next;
    next += 4 * layers;
    for (size_t i = 0; i < layers; ++i) {
      const uint32_t size = laz::LoadLe<uint32_t>(sizes + 4 * i);
      if (size > static_cast<size_t>(end - next)) {
        return Status::Corrupt(ChunkPlace(chunk) + ": layer " + std::to_string(i) + " of " +
                               std::to_string(size) + " bytes runs past the chunk's end");
      }
      const bool use = size > 0 && wanted_layers_[i];
      if (use) {
        codec.layers()[i]->Init(next, next + size);
        active.push_back(codec.layers()[i]);
      }
      codec.set_active(i, use);
      next += size;
    }
    if (wanted_layers_[0] && laz::LoadLe<uint32_t>(sizes) == 0) {
      return Status::Corrupt(ChunkPlace(chunk) + ": the XY layer is empty");
    }
  }
  auto damaged = [&](uint64_t point) -> Status {
    for (const laz::DecodingCoder* coder : active) {
      if (coder->decoder().overrun_bytes() > kMaxOverrunBytes) {
        return Status::Corrupt(ChunkPlace(chunk) + ": compressed data ran out at point " +
                               std::to_string(c.first_point + point));
      }
      if (coder->decoder().corrupt() || codec.damaged()) {
        return Status::Corrupt(ChunkPlace(chunk) + ": damaged compressed data at point " +
                               std::to_string(c.first_point + point));
      }
    }
    return Status::Ok();
  };
  for (uint64_t i = 1; i < c.points; ++i) {
    codec.Code(records + i * record_bytes);
    if ((i & 1023) == 0) PB_RETURN_IF_ERROR(damaged(i));
  }
  return damaged(c.points - 1);
}

Status LazReader::Next(std::span<const uint8_t>* records) {
  *records = {};
  if (next_chunk_ >= chunks_.size()) return Status::Ok();
  const size_t record_bytes = layout_.record_bytes;
  const size_t max_chunks = 4 * static_cast<size_t>(tbb::this_task_arena::max_concurrency());
  size_t end = next_chunk_;
  uint64_t points = 0;
  while (end < chunks_.size() && end - next_chunk_ < max_chunks &&
         (end == next_chunk_ ||
          (points + chunks_[end].points) * record_bytes <= options_.max_batch_bytes)) {
    points += chunks_[end].points;
    ++end;
  }
  const size_t batch = end - next_chunk_;
  compressed_.resize(std::max(compressed_.size(), batch));
  for (size_t i = 0; i < batch; ++i) {
    const Chunk& c = chunks_[next_chunk_ + i];
    compressed_[i].resize(c.bytes);
    if (!in_->Seek(c.offset) || !in_->Read(compressed_[i].data(), c.bytes)) {
      PB_RETURN_IF_ERROR(in_->error());
      return Status::Corrupt(ChunkPlace(next_chunk_ + i) + ": truncated (file has " +
                             std::to_string(in_->size()) + " bytes)");
    }
  }
  records_.resize(points * record_bytes);
  std::vector<Status> statuses(batch, Status::Ok());
  tbb::parallel_for(size_t{0}, batch, [&](size_t i) {
    const size_t chunk = next_chunk_ + i;
    const uint64_t first = chunks_[chunk].first_point - chunks_[next_chunk_].first_point;
    statuses[i] = DecodeChunk(chunk, compressed_[i], records_.data() + first * record_bytes);
  });
  for (const Status& status : statuses) PB_RETURN_IF_ERROR(status);
  next_chunk_ = end;
  *records = records_;
  return Status::Ok();
}

}  // namespace pb
