#include "stages/geometry/io/laz_test_encoder.h"

#include <algorithm>
#include <cassert>
#include <cstring>
#include <random>

#include "stages/geometry/io/laz_chunk_codec.h"

namespace pb::laz {

void ArithmeticEncoder::EncodeBit(BitModel& m, uint32_t bit) {
  const uint32_t x = m.bit_0_prob * (length_ >> kBitLengthShift);
  if (bit == 0) {
    length_ = x;
    ++m.bit_0_count;
  } else {
    const uint32_t init_base = base_;
    base_ += x;
    length_ -= x;
    if (init_base > base_) PropagateCarry();
  }
  if (length_ < kMinLength) Renormalize();
  if (--m.bits_until_update == 0) m.Update();
}

void ArithmeticEncoder::EncodeSymbol(SymbolModel& m, uint32_t symbol) {
  assert(symbol < m.symbols_);
  const uint32_t init_base = base_;
  if (symbol == m.last_symbol_) {
    const uint32_t x = m.distribution_[symbol] * (length_ >> kSymbolLengthShift);
    base_ += x;
    length_ -= x;
  } else {
    length_ >>= kSymbolLengthShift;
    const uint32_t x = m.distribution_[symbol] * length_;
    base_ += x;
    length_ = m.distribution_[symbol + 1] * length_ - x;
  }
  if (init_base > base_) PropagateCarry();
  if (length_ < kMinLength) Renormalize();
  ++m.symbol_count_[symbol];
  if (--m.symbols_until_update_ == 0) m.Update();
}

void ArithmeticEncoder::WriteBits(uint32_t bits, uint32_t value) {
  if (bits > 19) {
    WriteBits(16, value & 0xFFFF);
    value >>= 16;
    bits -= 16;
  }
  const uint32_t init_base = base_;
  base_ += value * (length_ >>= bits);
  if (init_base > base_) PropagateCarry();
  if (length_ < kMinLength) Renormalize();
}

void ArithmeticEncoder::WriteInt(uint32_t value) {
  WriteBits(16, value & 0xFFFF);
  WriteBits(16, value >> 16);
}

void ArithmeticEncoder::EncodeInt(IntegerModel& ic, int32_t prediction, int32_t real,
                                  uint32_t context) {
  int32_t corrector =
      static_cast<int32_t>(static_cast<uint32_t>(real) - static_cast<uint32_t>(prediction));
  if (ic.corr_range != 0) {
    if (corrector < ic.corr_min) {
      corrector += static_cast<int32_t>(ic.corr_range);
    } else if (corrector > ic.corr_max) {
      corrector -= static_cast<int32_t>(ic.corr_range);
    }
  }
  uint32_t magnitude =
      corrector <= 0 ? 0u - static_cast<uint32_t>(corrector) : static_cast<uint32_t>(corrector) - 1;
  uint32_t k = 0;
  while (magnitude) {
    magnitude >>= 1;
    ++k;
  }
  EncodeSymbol(ic.k_models[context], k);
  ic.k = k;
  if (k == 0) {
    EncodeBit(ic.corrector_0, static_cast<uint32_t>(corrector));
    return;
  }
  if (k >= 32) return;
  const uint32_t c = corrector < 0 ? static_cast<uint32_t>(corrector) + ((1u << k) - 1)
                                   : static_cast<uint32_t>(corrector) - 1;
  if (k <= ic.bits_high) {
    EncodeSymbol(ic.correctors[k - 1], c);
  } else {
    const uint32_t low_bits = k - ic.bits_high;
    EncodeSymbol(ic.correctors[k - 1], c >> low_bits);
    WriteBits(low_bits, c & ((1u << low_bits) - 1));
  }
}

std::vector<uint8_t> ArithmeticEncoder::Done() {
  const uint32_t init_base = base_;
  bool another_byte = true;
  if (length_ > 2 * kMinLength) {
    base_ += kMinLength;
    length_ = kMinLength >> 1;
  } else {
    base_ += kMinLength >> 1;
    length_ = kMinLength >> 9;
    another_byte = false;
  }
  if (init_base > base_) PropagateCarry();
  Renormalize();
  // The decoder reads four bytes ahead.
  out_.push_back(0);
  out_.push_back(0);
  if (another_byte) out_.push_back(0);
  std::vector<uint8_t> out;
  out.swap(out_);
  base_ = 0;
  length_ = kMaxLength;
  return out;
}

void ArithmeticEncoder::PropagateCarry() {
  for (size_t i = out_.size(); i-- > 0;) {
    if (out_[i] == 0xFF) {
      out_[i] = 0;
    } else {
      ++out_[i];
      return;
    }
  }
}

void ArithmeticEncoder::Renormalize() {
  do {
    out_.push_back(static_cast<uint8_t>(base_ >> 24));
    base_ <<= 8;
  } while ((length_ <<= 8) < kMinLength);
}

namespace {

template <typename T>
T Get(const std::string& bytes, size_t offset) {
  T value;
  std::memcpy(&value, bytes.data() + offset, sizeof(T));
  return value;
}
template <typename T>
void Append(std::string* bytes, T value) {
  bytes->append(reinterpret_cast<const char*>(&value), sizeof(T));
}
template <typename T>
void Set(std::string* bytes, size_t offset, T value) {
  std::memcpy(bytes->data() + offset, &value, sizeof(T));
}
void AppendBytes(std::string* bytes, const std::vector<uint8_t>& more) {
  bytes->append(reinterpret_cast<const char*>(more.data()), more.size());
}

std::string VlrHeader(const char* user_id, uint16_t record_id, uint16_t payload_bytes,
                      const char* description) {
  std::string header(54, '\0');
  std::strncpy(header.data() + 2, user_id, 16);
  Set<uint16_t>(&header, 18, record_id);
  Set<uint16_t>(&header, 20, payload_bytes);
  std::strncpy(header.data() + 22, description, 32);
  return header;
}

std::vector<Item> ItemsFor(int format, size_t record_bytes) {
  std::vector<Item> items;
  size_t standard = 0;
  auto add = [&](uint16_t type, uint16_t size, uint16_t version) {
    items.push_back({type, size, version});
    standard += size;
  };
  if (format <= 3) {
    add(Item::kPoint10, 20, 2);
    if (format == 1 || format == 3) add(Item::kGpsTime11, 8, 2);
    if (format >= 2) add(Item::kRgb12, 6, 2);
  } else {
    add(Item::kPoint14, 30, 3);
    if (format == 7) add(Item::kRgb14, 6, 3);
    if (format == 8) add(Item::kRgbNir14, 8, 3);
  }
  assert(record_bytes >= standard);
  if (record_bytes > standard) {
    const uint16_t extra = static_cast<uint16_t>(record_bytes - standard);
    items.push_back({format <= 3 ? Item::kByte : Item::kByte14, extra,
                     static_cast<uint16_t>(format <= 3 ? 2 : 3)});
  }
  return items;
}

std::string EncodeChunk(const std::vector<Item>& items, const uint8_t* records, size_t record_bytes,
                        size_t points) {
  std::string out(reinterpret_cast<const char*>(records), record_bytes);
  ChunkCodec<EncodingCoder> codec(items, records);
  std::vector<uint8_t> record(record_bytes);
  for (size_t i = 1; i < points; ++i) {
    std::memcpy(record.data(), records + i * record_bytes, record_bytes);
    codec.Code(record.data());
  }
  if (!codec.layered()) {
    AppendBytes(&out, codec.stream().Done());
    return out;
  }
  Append<uint32_t>(&out, static_cast<uint32_t>(points - 1));
  std::vector<std::vector<uint8_t>> layers;
  for (EncodingCoder* layer : codec.layers()) layers.push_back(layer->Done());
  for (const auto& layer : layers) Append<uint32_t>(&out, static_cast<uint32_t>(layer.size()));
  for (const auto& layer : layers) AppendBytes(&out, layer);
  return out;
}

size_t StandardBytes(int format) {
  static constexpr size_t kSizes[] = {20, 28, 26, 34, 57, 63, 30, 36, 38};
  return kSizes[format];
}

}  // namespace

std::string CompressLas(const std::string& las, const LazWriteOptions& options) {
  const uint16_t header_bytes = Get<uint16_t>(las, 94);
  const uint32_t point_offset = Get<uint32_t>(las, 96);
  const int format = static_cast<uint8_t>(las[104]);
  const uint16_t record_bytes = Get<uint16_t>(las, 105);
  const int minor = las[25];
  uint64_t count = Get<uint32_t>(las, 107);
  if (minor >= 4 && header_bytes >= 375 && Get<uint64_t>(las, 247) != 0)
    count = Get<uint64_t>(las, 247);
  assert(format <= 3 || (format >= 6 && format <= 8));
  assert(!options.copc || (minor == 4 && format >= 6));
  const std::vector<Item> items = ItemsFor(format, record_bytes);
  const bool variable = !options.chunk_points.empty() || options.copc;
  assert(!options.not_chunked || format <= 3);
  std::vector<uint32_t> chunk_points = options.chunk_points;
  if (options.not_chunked) {
    chunk_points = {static_cast<uint32_t>(count)};
  } else if (chunk_points.empty()) {
    const uint32_t size = options.copc ? 1000 : options.chunk_size;
    for (uint64_t done = 0; done < count; done += size)
      chunk_points.push_back(static_cast<uint32_t>(std::min<uint64_t>(size, count - done)));
  }

  // The laszip VLR.
  std::string laszip;
  Append<uint16_t>(&laszip, options.not_chunked ? 1 : format <= 3 ? 2 : 3);
  Append<uint16_t>(&laszip, 0);
  laszip += std::string{3, 4};
  Append<uint16_t>(&laszip, 0);
  Append<uint32_t>(&laszip, 0);
  Append<uint32_t>(&laszip, options.not_chunked ? 0 : variable ? 0xFFFFFFFFu : options.chunk_size);
  Append<int64_t>(&laszip, -1);
  Append<int64_t>(&laszip, -1);
  Append<uint16_t>(&laszip, static_cast<uint16_t>(items.size()));
  for (const Item& item : items) {
    Append<uint16_t>(&laszip, item.type);
    Append<uint16_t>(&laszip, item.size);
    Append<uint16_t>(&laszip, item.version);
  }

  std::string out = las.substr(0, header_bytes);
  std::string vlrs;
  uint32_t vlr_count = Get<uint32_t>(las, 100);
  if (options.copc) {
    vlrs += VlrHeader("copc", 1, 160, "copc info");
    vlrs += std::string(160, '\0');  // filled in below
    ++vlr_count;
  }
  vlrs += las.substr(header_bytes, point_offset - header_bytes);
  vlrs += VlrHeader("laszip encoded", 22204, static_cast<uint16_t>(laszip.size()),
                    "by pointbake tests");
  vlrs += laszip;
  ++vlr_count;
  out += vlrs;
  out[104] = static_cast<char>(format | 0x80);
  Set<uint32_t>(&out, 96, static_cast<uint32_t>(out.size()));
  Set<uint32_t>(&out, 100, vlr_count);

  const auto* records = reinterpret_cast<const uint8_t*>(las.data() + point_offset);
  if (options.not_chunked) {
    out += EncodeChunk(items, records, record_bytes, count);
    return out;
  }
  const size_t table_offset_at = out.size();
  Append<int64_t>(&out, -1);
  std::vector<uint32_t> chunk_bytes;
  std::vector<uint64_t> chunk_offsets;
  uint64_t first = 0;
  for (uint32_t points : chunk_points) {
    chunk_offsets.push_back(out.size());
    const std::string chunk =
        EncodeChunk(items, records + first * record_bytes, record_bytes, points);
    chunk_bytes.push_back(static_cast<uint32_t>(chunk.size()));
    out += chunk;
    first += points;
  }
  assert(first == count);
  const uint64_t table_offset = out.size();
  Append<uint32_t>(&out, 0);
  Append<uint32_t>(&out, static_cast<uint32_t>(chunk_points.size()));
  {
    ArithmeticEncoder encoder;
    IntegerModel ic(32, 2);
    int32_t last_points = 0, last_bytes = 0;
    for (size_t i = 0; i < chunk_points.size(); ++i) {
      if (variable) {
        encoder.EncodeInt(ic, last_points, static_cast<int32_t>(chunk_points[i]), 0);
        last_points = static_cast<int32_t>(chunk_points[i]);
      }
      encoder.EncodeInt(ic, last_bytes, static_cast<int32_t>(chunk_bytes[i]), 1);
      last_bytes = static_cast<int32_t>(chunk_bytes[i]);
    }
    AppendBytes(&out, encoder.Done());
  }
  if (options.table_offset_at_end) {
    Append<uint64_t>(&out, table_offset);
  } else {
    Set<uint64_t>(&out, table_offset_at, table_offset);
  }
  if (options.copc) {
    // Hierarchy EVLR: one page listing each chunk as a node of the octree
    // (key level x y z, offset, bytes, points): the root, then up to
    // eight children at level 1.
    assert(chunk_points.size() <= 9);
    const uint64_t evlr_offset = out.size();
    std::string page;
    for (size_t i = 0; i < chunk_points.size(); ++i) {
      const int32_t child = static_cast<int32_t>(i) - 1;
      const int32_t key[4] = {i == 0 ? 0 : 1, i == 0 ? 0 : child & 1, i == 0 ? 0 : (child >> 1) & 1,
                              i == 0 ? 0 : (child >> 2) & 1};
      for (int32_t k : key) Append<int32_t>(&page, k);
      Append<uint64_t>(&page, chunk_offsets[i]);
      Append<int32_t>(&page, static_cast<int32_t>(chunk_bytes[i]));
      Append<int32_t>(&page, static_cast<int32_t>(chunk_points[i]));
    }
    std::string evlr(60, '\0');
    std::strncpy(evlr.data() + 2, "copc", 16);
    Set<uint16_t>(&evlr, 18, 1000);
    Set<uint64_t>(&evlr, 20, page.size());
    std::strncpy(evlr.data() + 28, "EPT hierarchy", 32);
    out += evlr;
    out += page;
    Set<uint64_t>(&out, 235, evlr_offset);
    Set<uint32_t>(&out, 243, Get<uint32_t>(out, 243) + 1);
    // The info VLR: center and halfsize from the header's box, spacing,
    // root hierarchy page, GPS time range (left 0).
    const size_t info = header_bytes + 54;
    double min[3], max[3];
    for (int axis = 0; axis < 3; ++axis) {
      max[axis] = Get<double>(out, 179 + 16 * axis);
      min[axis] = Get<double>(out, 187 + 16 * axis);
      Set<double>(&out, info + 8 * axis, 0.5 * (min[axis] + max[axis]));
    }
    Set<double>(&out, info + 24,
                0.5 * std::max({max[0] - min[0], max[1] - min[1], max[2] - min[2]}));
    Set<double>(&out, info + 32, 1.0);
    Set<uint64_t>(&out, info + 40, evlr_offset + 60);
    Set<uint64_t>(&out, info + 48, page.size());
  }
  return out;
}

std::string SyntheticAirborneLas(int format, size_t points, size_t extra_bytes, uint32_t seed,
                                 int scanner_channels) {
  const int minor = format >= 6 ? 4 : 2;
  const size_t header_bytes = minor == 4 ? 375 : 227;
  const size_t record_bytes = StandardBytes(format) + extra_bytes;
  std::string las(header_bytes + record_bytes * points, '\0');
  std::memcpy(las.data(), "LASF", 4);
  las[24] = 1;
  las[25] = static_cast<char>(minor);
  Set<uint16_t>(&las, 94, static_cast<uint16_t>(header_bytes));
  Set<uint32_t>(&las, 96, static_cast<uint32_t>(header_bytes));
  las[104] = static_cast<char>(format);
  Set<uint16_t>(&las, 105, static_cast<uint16_t>(record_bytes));
  Set<uint32_t>(&las, 107, minor == 4 ? 0 : static_cast<uint32_t>(points));
  if (minor == 4) Set<uint64_t>(&las, 247, points);
  const double scale = 0.01;
  const double offsets[3] = {652000, 5412000, 0};
  for (int axis = 0; axis < 3; ++axis) {
    Set<double>(&las, 131 + 8 * axis, scale);
    Set<double>(&las, 155 + 8 * axis, offsets[axis]);
  }
  std::mt19937 random(seed);
  auto uniform = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(random); };
  int32_t x = 30000, y = 40000, z = 2000;
  int32_t min[3] = {INT32_MAX, INT32_MAX, INT32_MAX}, max[3] = {INT32_MIN, INT32_MIN, INT32_MIN};
  double times[2] = {1000.0, 90000.0};
  int line = 0, returns = 1, return_number = 1, channel = 0;
  uint16_t rgb[3] = {1000, 2000, 3000};
  int16_t scan_angle = 0;
  uint16_t point_source = 7;
  uint8_t classification = 2;
  for (size_t i = 0; i < points; ++i) {
    if (return_number >= returns) {  // a new pulse
      return_number = 1;
      returns = uniform(0, 99) < 70   ? 1
                : uniform(0, 99) < 90 ? uniform(2, 3)
                                      : uniform(4, format >= 6 ? 15 : 7);
      if (uniform(0, 199) == 0) line ^= 1;
      times[line] += uniform(0, 99) < 95 ? 1.0e-5 : uniform(0, 99) < 50 ? 3.0e-5 : 7.5;
      x += uniform(5, 60);
      if (uniform(0, 299) == 0) y += uniform(-5000, 5000);
      scan_angle = static_cast<int16_t>(scan_angle + uniform(-2, 2));
      if (uniform(0, 999) == 0) point_source = static_cast<uint16_t>(uniform(0, 65535));
      if (format >= 6 && uniform(0, 49) == 0) channel = uniform(0, scanner_channels - 1);
    } else {
      ++return_number;
    }
    y += uniform(-20, 20);
    z += uniform(-30, 30) - (return_number - 1) * 50;
    if (uniform(0, 9) == 0)
      classification = static_cast<uint8_t>(uniform(0, 99) < 80 ? uniform(1, 6) : uniform(0, 255));
    if (uniform(0, 2) == 0) {
      if (uniform(0, 3) == 0) {  // grey
        rgb[0] = rgb[1] = rgb[2] = static_cast<uint16_t>(uniform(0, 255) * 257);
      } else {
        for (uint16_t& c : rgb)
          c = static_cast<uint16_t>(std::clamp(c + uniform(-900, 900), 0, 65535));
      }
    }
    const int32_t xyz[3] = {x, y, z};
    for (int axis = 0; axis < 3; ++axis) {
      min[axis] = std::min(min[axis], xyz[axis]);
      max[axis] = std::max(max[axis], xyz[axis]);
    }
    const size_t at = header_bytes + i * record_bytes;
    uint8_t* r = reinterpret_cast<uint8_t*>(las.data() + at);
    Set<int32_t>(&las, at, x);
    Set<int32_t>(&las, at + 4, y);
    Set<int32_t>(&las, at + 8, z);
    Set<uint16_t>(&las, at + 12, static_cast<uint16_t>(uniform(0, 99) < 10 ? 0 : uniform(0, 4000)));
    const int edge = uniform(0, 99) == 0, direction = (i / 500) & 1;
    size_t gps_at, rgb_at = 0;
    if (format < 6) {
      r[14] = static_cast<uint8_t>((return_number & 7) | ((returns & 7) << 3) | (direction << 6) |
                                   (edge << 7));
      r[15] = classification;
      r[16] = static_cast<uint8_t>(static_cast<int8_t>(std::clamp(scan_angle / 100, -90, 90)));
      r[17] = static_cast<uint8_t>(uniform(0, 9) == 0 ? uniform(0, 255) : 0);
      Set<uint16_t>(&las, at + 18, point_source);
      gps_at = 20;
      if (format >= 2) rgb_at = format == 2 ? 20 : 28;
    } else {
      r[14] = static_cast<uint8_t>(return_number | (returns << 4));
      r[15] = static_cast<uint8_t>((uniform(0, 49) == 0 ? uniform(0, 15) : 0) | (channel << 4) |
                                   (direction << 6) | (edge << 7));
      r[16] = classification;
      r[17] = static_cast<uint8_t>(uniform(0, 9) == 0 ? uniform(0, 255) : 0);
      Set<int16_t>(&las, at + 18, scan_angle);
      Set<uint16_t>(&las, at + 20, point_source);
      gps_at = 22;
      if (format >= 7) rgb_at = 30;
    }
    if (format != 0 && format != 2) Set<double>(&las, at + gps_at, times[line]);
    if (rgb_at != 0) {
      for (int c = 0; c < 3; ++c) Set<uint16_t>(&las, at + rgb_at + 2 * c, rgb[c]);
    }
    if (format == 8) Set<uint16_t>(&las, at + 36, static_cast<uint16_t>(uniform(0, 65535)));
    for (size_t b = 0; b < extra_bytes; ++b) {
      r[StandardBytes(format) + b] = static_cast<uint8_t>(b == 0 ? i & 0xFF : uniform(0, 3));
    }
  }
  for (int axis = 0; axis < 3; ++axis) {
    Set<double>(&las, 179 + 16 * axis, max[axis] * scale + offsets[axis]);
    Set<double>(&las, 187 + 16 * axis, min[axis] * scale + offsets[axis]);
  }
  return las;
}

}  // namespace pb::laz
