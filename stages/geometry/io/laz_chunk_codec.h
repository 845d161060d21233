// A LAZ chunk's point codec: the item codecs of laz_items.h composed by the
// item list of the laszip VLR, for the pointwise compressor (one coded
// stream, items in record order) and the layered one (POINT14 v3: one
// stream per layer, the fields of each point spread over the layers;
// scanner channel contexts; spec: LASzip/design/specification.rst).
//
// Layers of a layered chunk, in stream order:
//   POINT14 (9): XY + returns + change flags, Z, classification, flags,
//                intensity, scan angle, user data, point source, GPS time
//   RGB14 (1): RGB.  RGBNIR14 (2): RGB, NIR.  BYTE14 (n): one per byte.
// A layer that is inactive (0 bytes in the chunk, or not requested by the
// reader) is not decoded: its fields keep the chunk's first point's values.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "stages/geometry/io/laz_items.h"

namespace pb::laz {

// One entry of the laszip VLR's item list.
struct Item {
  enum Type : uint16_t {
    kByte = 0,
    kPoint10 = 6,
    kGpsTime11 = 7,
    kRgb12 = 8,
    kPoint14 = 10,
    kRgb14 = 11,
    kRgbNir14 = 12,
    kByte14 = 14,
  };
  uint16_t type = 0;
  uint16_t size = 0;     // bytes of the record it covers
  uint16_t version = 0;  // 2 for pointwise, 3 for layered items
};

// The POINT14 fields, unpacked from / packed to the 30 record bytes.
struct Point14 {
  int32_t x = 0, y = 0, z = 0;
  uint16_t intensity = 0;
  uint32_t return_number = 0, number_of_returns = 0;
  uint32_t class_flags = 0, channel = 0, scan_direction = 0, edge = 0;
  uint32_t classification = 0, user_data = 0;
  int16_t scan_angle = 0;
  uint16_t point_source = 0;
  uint64_t gps_time = 0;  // the double's bits
  bool gps_time_change = false;

  static Point14 Unpack(const uint8_t* r) {
    Point14 p;
    p.x = LoadLe<int32_t>(r);
    p.y = LoadLe<int32_t>(r + 4);
    p.z = LoadLe<int32_t>(r + 8);
    p.intensity = LoadLe<uint16_t>(r + 12);
    p.return_number = r[14] & 15;
    p.number_of_returns = r[14] >> 4;
    p.class_flags = r[15] & 15;
    p.channel = (r[15] >> 4) & 3;
    p.scan_direction = (r[15] >> 6) & 1;
    p.edge = r[15] >> 7;
    p.classification = r[16];
    p.user_data = r[17];
    p.scan_angle = LoadLe<int16_t>(r + 18);
    p.point_source = LoadLe<uint16_t>(r + 20);
    p.gps_time = LoadLe<uint64_t>(r + 22);
    return p;
  }
  void Pack(uint8_t* r) const {
    StoreLe(r, x);
    StoreLe(r + 4, y);
    StoreLe(r + 8, z);
    StoreLe(r + 12, intensity);
    r[14] = static_cast<uint8_t>(return_number | (number_of_returns << 4));
    r[15] =
        static_cast<uint8_t>(class_flags | (channel << 4) | (scan_direction << 6) | (edge << 7));
    r[16] = static_cast<uint8_t>(classification);
    r[17] = static_cast<uint8_t>(user_data);
    StoreLe(r + 18, scan_angle);
    StoreLe(r + 20, point_source);
    StoreLe(r + 22, gps_time);
  }
};

template <class C>
class Point14Codec {
 public:
  enum Layer {
    kXY,
    kZ,
    kClassification,
    kFlags,
    kIntensity,
    kScanAngle,
    kUserData,
    kPointSource,
    kGpsTime,
    kLayers
  };

  explicit Point14Codec(const uint8_t* first) {
    const Point14 p = Point14::Unpack(first);
    current_ = p.channel;
    contexts_[current_] = std::make_unique<Context>(p);
  }

  C& layer(int i) { return layers_[i]; }
  void set_active(int i, bool active) { active_[i] = active; }
  uint32_t channel() const { return current_; }
  bool damaged() const {
    for (const auto& context : contexts_) {
      if (context && context->gps.damaged()) return true;
    }
    return false;
  }

  void Code(uint8_t* record) {
    [[maybe_unused]] Point14 t;
    if constexpr (C::kEncoding) t = Point14::Unpack(record);
    C& xy = layers_[kXY];
    Context* ctx = contexts_[current_].get();
    const Point14& previous = ctx->last;
    const uint32_t lpr = (previous.return_number == 1 ? 1u : 0u) +
                         (previous.return_number >= previous.number_of_returns ? 2u : 0u) +
                         (previous.gps_time_change ? 4u : 0u);
    uint32_t changed = 0;
    if constexpr (C::kEncoding) {
      const Point14& ref =
          t.channel != current_ && contexts_[t.channel] ? contexts_[t.channel]->last : previous;
      const uint32_t last_r = ref.return_number;
      const uint32_t r_code = t.return_number == last_r                 ? 0
                              : t.return_number == ((last_r + 1) & 15)  ? 1
                              : t.return_number == ((last_r + 15) & 15) ? 2
                                                                        : 3;
      changed = (static_cast<uint32_t>(t.channel != current_) << 6) |
                (static_cast<uint32_t>(t.point_source != ref.point_source) << 5) |
                (static_cast<uint32_t>(t.gps_time != ref.gps_time) << 4) |
                (static_cast<uint32_t>(t.scan_angle != ref.scan_angle) << 3) |
                (static_cast<uint32_t>(t.number_of_returns != ref.number_of_returns) << 2) | r_code;
    }
    changed = xy.Symbol(ctx->changed_values[lpr], changed);
    if (changed & 64) {
      const uint32_t diff = xy.Symbol(ctx->scanner_channel, (t.channel + 3 - current_) & 3);
      const uint32_t channel = (current_ + diff + 1) & 3;
      if (!contexts_[channel]) contexts_[channel] = std::make_unique<Context>(ctx->last);
      current_ = channel;
      ctx = contexts_[channel].get();
      ctx->last.channel = channel;
    }
    Point14& p = ctx->last;
    const bool point_source_change = changed & 32;
    const uint32_t gps_change = (changed >> 4) & 1;
    const bool scan_angle_change = changed & 8;

    const uint32_t last_n = p.number_of_returns, last_r = p.return_number;
    uint32_t n = last_n;
    if (changed & 4) {
      n = xy.Symbol(ctx->number_of_returns[last_n], t.number_of_returns);
      p.number_of_returns = n;
    }
    uint32_t r;
    switch (changed & 3) {
      case 0:
        r = last_r;
        break;
      case 1:
        r = (last_r + 1) & 15;
        break;
      case 2:
        r = (last_r + 15) & 15;
        break;
      default:
        if (gps_change) {
          r = xy.Symbol(ctx->return_number[last_r], t.return_number);
        } else {
          const uint32_t step =
              xy.Symbol(ctx->return_gps_same, (t.return_number - last_r - 2) & 15);
          r = (last_r + step + 2) & 15;
        }
    }
    p.return_number = r;
    const uint32_t m = kReturnMap6[n][r];
    const uint32_t l = kReturnLevel8Ctx[n][r];
    const uint32_t cpr = (r == 1 ? 2u : 0u) + (r >= n ? 1u : 0u);
    const uint32_t single = n == 1;

    const uint32_t median_index = (m << 1) | gps_change;
    const int32_t dx =
        xy.Int(ctx->ic_dx, ctx->x_median[median_index].Get(), WrapSub(t.x, p.x), single);
    p.x = WrapAdd(p.x, dx);
    ctx->x_median[median_index].Add(dx);
    uint32_t k = ctx->ic_dx.k;
    const int32_t dy = xy.Int(ctx->ic_dy, ctx->y_median[median_index].Get(), WrapSub(t.y, p.y),
                              single + (k < 20 ? k & ~1u : 20));
    p.y = WrapAdd(p.y, dy);
    ctx->y_median[median_index].Add(dy);
    if (active_[kZ]) {
      k = (ctx->ic_dx.k + ctx->ic_dy.k) / 2;
      p.z = layers_[kZ].Int(ctx->ic_z, ctx->last_z[l], t.z, single + (k < 18 ? k & ~1u : 18));
      ctx->last_z[l] = p.z;
    }
    if (active_[kClassification]) {
      const uint32_t context = ((p.classification & 0x1F) << 1) + (cpr == 3 ? 1 : 0);
      p.classification =
          layers_[kClassification].Symbol(ctx->classification[context], t.classification);
    }
    if (active_[kFlags]) {
      const uint32_t last_flags = (p.edge << 5) | (p.scan_direction << 4) | p.class_flags;
      const uint32_t flags = layers_[kFlags].Symbol(
          ctx->flags[last_flags], (t.edge << 5) | (t.scan_direction << 4) | t.class_flags);
      p.edge = (flags >> 5) & 1;
      p.scan_direction = (flags >> 4) & 1;
      p.class_flags = flags & 15;
    }
    if (active_[kIntensity]) {
      const uint32_t index = (cpr << 1) | gps_change;
      p.intensity = static_cast<uint16_t>(
          layers_[kIntensity].Int(ctx->ic_intensity, ctx->last_intensity[index], t.intensity, cpr));
      ctx->last_intensity[index] = p.intensity;
    }
    if (active_[kScanAngle] && scan_angle_change) {
      p.scan_angle = static_cast<int16_t>(
          layers_[kScanAngle].Int(ctx->ic_scan_angle, p.scan_angle, t.scan_angle, gps_change));
    }
    if (active_[kUserData]) {
      p.user_data = layers_[kUserData].Symbol(ctx->user_data[p.user_data / 4], t.user_data);
    }
    if (active_[kPointSource] && point_source_change) {
      p.point_source = static_cast<uint16_t>(
          layers_[kPointSource].Int(ctx->ic_point_source, p.point_source, t.point_source, 0));
    }
    if (active_[kGpsTime] && gps_change) p.gps_time = ctx->gps.Code(layers_[kGpsTime], t.gps_time);
    if constexpr (!C::kEncoding) p.Pack(record);
    p.gps_time_change = gps_change;
  }

 private:
  struct Context {
    explicit Context(const Point14& first) : last(first), gps(true, first.gps_time) {
      last.gps_time_change = false;
      last_intensity.fill(first.intensity);
      last_z.fill(first.z);
    }
    Point14 last;
    std::array<uint16_t, 8> last_intensity;
    std::array<Median5, 12> x_median{};
    std::array<Median5, 12> y_median{};
    std::array<int32_t, 8> last_z;
    std::array<SymbolModel, 8> changed_values{SymbolModel(128), SymbolModel(128), SymbolModel(128),
                                              SymbolModel(128), SymbolModel(128), SymbolModel(128),
                                              SymbolModel(128), SymbolModel(128)};
    SymbolModel scanner_channel{3};
    LazySymbolModels number_of_returns{16, 16};
    LazySymbolModels return_number{16, 16};
    SymbolModel return_gps_same{13};
    IntegerModel ic_dx{32, 2};
    IntegerModel ic_dy{32, 22};
    IntegerModel ic_z{32, 20};
    LazySymbolModels classification{64, 256};
    LazySymbolModels flags{64, 64};
    LazySymbolModels user_data{64, 256};
    IntegerModel ic_intensity{16, 4};
    IntegerModel ic_scan_angle{16, 2};
    IntegerModel ic_point_source{16};
    GpsTimeCodec<C> gps;
  };

  std::array<C, kLayers> layers_;
  std::array<bool, kLayers> active_{true, true, true, true, true, true, true, true, true};
  std::array<std::unique_ptr<Context>, 4> contexts_;
  uint32_t current_ = 0;
};

// A layered item other than POINT14 (RGB, NIR, extra bytes): models and
// last values per scanner channel, a new channel's started from the
// previous channel's last values. As LASzip does it (and so the files in
// the wild are): when the point returns to a channel seen before, that
// point is still predicted from, and updates, the previous channel's last
// values, with the returning channel's models; the next point of the
// channel uses its own last values again.
template <class Codec>
class PerChannel {
 public:
  PerChannel(uint32_t channel, const uint8_t* first, size_t bytes)
      : bytes_(bytes), current_(channel) {
    contexts_[channel] = std::make_unique<Codec>(first, bytes);
  }

  struct Selected {
    Codec* models;
    uint8_t* last;
  };
  Selected Switch(uint32_t channel) {
    uint8_t* last = contexts_[current_]->last();
    if (channel != current_) {
      current_ = channel;
      if (!contexts_[channel]) {
        contexts_[channel] = std::make_unique<Codec>(last, bytes_);
        last = contexts_[channel]->last();
      }
    }
    return {contexts_[current_].get(), last};
  }

 private:
  size_t bytes_;
  uint32_t current_;
  std::array<std::unique_ptr<Codec>, 4> contexts_;
};

// All items of a record. Construct with the chunk's first (raw) record;
// then, per further point, Code(record).
template <class C>
class ChunkCodec {
 public:
  // `items` must have passed CheckItems (laz.h).
  ChunkCodec(const std::vector<Item>& items, const uint8_t* first) {
    size_t offset = 0;
    for (const Item& item : items) {
      Part part{item.type, offset, item.size};
      const uint8_t* bytes = first + offset;
      switch (item.type) {
        case Item::kPoint10:
          point10_ = std::make_unique<Point10Codec<C>>(bytes);
          break;
        case Item::kGpsTime11:
          gps_ = std::make_unique<GpsTimeCodec<C>>(false, LoadLe<uint64_t>(bytes));
          break;
        case Item::kRgb12:
          rgb12_ = std::make_unique<RgbCodec<C>>(bytes);
          break;
        case Item::kByte:
          bytes10_ = std::make_unique<ExtraBytesCodec<C>>(bytes, item.size);
          break;
        case Item::kPoint14:
          point14_ = std::make_unique<Point14Codec<C>>(bytes);
          break;
        case Item::kRgb14:
        case Item::kRgbNir14: {
          const uint32_t channel = point14_->channel();
          rgb14_ = std::make_unique<PerChannel<RgbCodec<C>>>(channel, bytes, 6);
          if (item.type == Item::kRgbNir14)
            nir14_ = std::make_unique<PerChannel<NirCodec<C>>>(channel, bytes + 6, 2);
          break;
        }
        case Item::kByte14:
          bytes14_ = std::make_unique<PerChannel<ExtraBytesCodec<C>>>(point14_->channel(), bytes,
                                                                      item.size);
          break;
      }
      parts_.push_back(part);
      offset += item.size;
    }
    layered_ = point14_ != nullptr;
    if (layered_) {
      for (int i = 0; i < Point14Codec<C>::kLayers; ++i) layers_.push_back(&point14_->layer(i));
      for (const Part& part : parts_) {
        if (part.type == Item::kRgb14) layers_.push_back(&rgb_layer_);
        if (part.type == Item::kRgbNir14) {
          layers_.push_back(&rgb_layer_);
          layers_.push_back(&nir_layer_);
        }
        if (part.type == Item::kByte14) {
          byte_layers_.resize(part.bytes);
          for (C& layer : byte_layers_) layers_.push_back(&layer);
        }
      }
      active_.assign(layers_.size(), true);
    }
  }

  bool layered() const { return layered_; }
  // Pointwise: the one stream. Layered: the streams in chunk order.
  C& stream() { return stream_; }
  const std::vector<C*>& layers() const { return layers_; }
  void set_active(size_t layer, bool active) {
    active_[layer] = active;
    if (layer < Point14Codec<C>::kLayers) point14_->set_active(static_cast<int>(layer), active);
  }
  bool damaged() const { return (gps_ && gps_->damaged()) || (point14_ && point14_->damaged()); }

  void Code(uint8_t* record) {
    if (!layered_) {
      for (const Part& part : parts_) {
        uint8_t* bytes = record + part.offset;
        switch (part.type) {
          case Item::kPoint10:
            point10_->Code(stream_, bytes);
            break;
          case Item::kGpsTime11: {
            const uint64_t time = gps_->Code(stream_, C::kEncoding ? LoadLe<uint64_t>(bytes) : 0);
            if constexpr (!C::kEncoding) StoreLe(bytes, time);
            break;
          }
          case Item::kRgb12:
            rgb12_->Code(stream_, bytes);
            break;
          case Item::kByte:
            bytes10_->Code(stream_, bytes);
            break;
        }
      }
      return;
    }
    point14_->Code(record);
    const uint32_t channel = point14_->channel();
    size_t layer = Point14Codec<C>::kLayers;
    for (const Part& part : parts_) {
      uint8_t* bytes = record + part.offset;
      if (part.type == Item::kRgb14 || part.type == Item::kRgbNir14) {
        const auto rgb = rgb14_->Switch(channel);
        if (active_[layer]) {
          rgb.models->CodeWith(rgb_layer_, bytes, rgb.last);
        } else if constexpr (!C::kEncoding) {
          std::memcpy(bytes, rgb.last, 6);
        }
        ++layer;
        if (part.type == Item::kRgbNir14) {
          const auto nir = nir14_->Switch(channel);
          if (active_[layer]) {
            nir.models->CodeWith(nir_layer_, bytes + 6, nir.last);
          } else if constexpr (!C::kEncoding) {
            std::memcpy(bytes + 6, nir.last, 2);
          }
          ++layer;
        }
      } else if (part.type == Item::kByte14) {
        const auto extra = bytes14_->Switch(channel);
        for (size_t i = 0; i < part.bytes; ++i, ++layer) {
          if (active_[layer]) {
            extra.models->CodeByteWith(byte_layers_[i], i, bytes + i, extra.last);
          } else if constexpr (!C::kEncoding) {
            bytes[i] = extra.last[i];
          }
        }
      }
    }
  }

 private:
  struct Part {
    uint16_t type;
    size_t offset;
    size_t bytes;
  };
  std::vector<Part> parts_;
  bool layered_ = false;
  C stream_;
  std::unique_ptr<Point10Codec<C>> point10_;
  std::unique_ptr<GpsTimeCodec<C>> gps_;
  std::unique_ptr<RgbCodec<C>> rgb12_;
  std::unique_ptr<ExtraBytesCodec<C>> bytes10_;
  std::unique_ptr<Point14Codec<C>> point14_;
  std::unique_ptr<PerChannel<RgbCodec<C>>> rgb14_;
  std::unique_ptr<PerChannel<NirCodec<C>>> nir14_;
  std::unique_ptr<PerChannel<ExtraBytesCodec<C>>> bytes14_;
  C rgb_layer_;
  C nir_layer_;
  std::vector<C> byte_layers_;
  std::vector<C*> layers_;
  std::vector<bool> active_;
};

}  // namespace pb::laz
