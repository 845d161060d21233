// The LAZ item codecs: how each part of a LAS point record is predicted and
// coded, for the pointwise compressor (items POINT10, GPSTIME11, RGB12 and
// BYTE, version 2: point formats 0-3) and the layered one (POINT14, RGB14,
// RGBNIR14 and BYTE14, version 3: formats 6-8). Written from the LASzip
// format description (M. Isenburg, "LASzip: lossless compression of LiDAR
// data", PE&RS 2013, sections 3.1-3.4, for version 2; LASzip/design/
// specification.rst, "LASzip for LAS 1.4 (native extension)", for version
// 3, whose return map and return level tables are copied below as data).
//
// Each codec is a template over a coder with the calls of
// laz::DecodingCoder: the reader instantiates it with the decoder, the
// tests with an encoder, so the encoder cannot drift from the decoder (and
// the npm laz-perf decoder checks both against the format). In encoding
// mode a codec also computes what to code (which fields changed, the
// multiplier of a GPS time delta); that code sits in `if constexpr
// (C::kEncoding)` blocks and is not compiled into the reader.
//
// Records are the LAS point record bytes (little-endian):
//   POINT10 (20 bytes): X Y Z int32, intensity u16 @12, returns byte @14
//     (return 0-2, number 3-5, scan direction 6, edge 7), class @15,
//     scan angle int8 @16, user data @17, point source u16 @18.
//   POINT14 (30 bytes): X Y Z, intensity @12, returns @14 (return 0-3,
//     number 4-7), flags @15 (class flags 0-3, scanner channel 4-5, scan
//     direction 6, edge 7), class @16, user data @17, scan angle int16 @18,
//     point source @20, GPS time double @22.
//   GPSTIME11: double (8). RGB12 / RGB14: R G B u16 (6). RGBNIR14: + NIR (8).
#pragma once

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "stages/geometry/io/laz_codec.h"

namespace pb::laz {

template <typename T>
inline T LoadLe(const uint8_t* bytes) {
  T value;
  std::memcpy(&value, bytes, sizeof(T));
  static_assert(std::endian::native == std::endian::little,
                "LAZ codecs assume a little-endian host");
  return value;
}
template <typename T>
inline void StoreLe(uint8_t* bytes, T value) {
  std::memcpy(bytes, &value, sizeof(T));
}

inline int32_t WrapAdd(int32_t a, int32_t b) {
  return static_cast<int32_t>(static_cast<uint32_t>(a) + static_cast<uint32_t>(b));
}
inline int32_t WrapSub(int32_t a, int32_t b) {
  return static_cast<int32_t>(static_cast<uint32_t>(a) - static_cast<uint32_t>(b));
}
inline int32_t WrapMul(int32_t a, int32_t b) {
  return static_cast<int32_t>(static_cast<uint32_t>(a) * static_cast<uint32_t>(b));
}
inline uint8_t ClampByte(int32_t n) {
  return static_cast<uint8_t>(n < 0 ? 0 : (n > 255 ? 255 : n));
}

// The running median of the last five values (the X/Y delta predictor).
class Median5 {
 public:
  int32_t Get() const { return values_[2]; }
  void Add(int32_t v) {
    int32_t* a = values_.data();
    if (high_) {
      if (v < a[2]) {
        a[4] = a[3];
        a[3] = a[2];
        if (v < a[0]) {
          a[2] = a[1];
          a[1] = a[0];
          a[0] = v;
        } else if (v < a[1]) {
          a[2] = a[1];
          a[1] = v;
        } else {
          a[2] = v;
        }
      } else {
        if (v < a[3]) {
          a[4] = a[3];
          a[3] = v;
        } else {
          a[4] = v;
        }
        high_ = false;
      }
    } else {
      if (a[2] < v) {
        a[0] = a[1];
        a[1] = a[2];
        if (a[4] < v) {
          a[2] = a[3];
          a[3] = a[4];
          a[4] = v;
        } else if (a[3] < v) {
          a[2] = a[3];
          a[3] = v;
        } else {
          a[2] = v;
        }
      } else {
        if (a[1] < v) {
          a[0] = a[1];
          a[1] = v;
        } else {
          a[0] = v;
        }
        high_ = true;
      }
    }
  }

 private:
  std::array<int32_t, 5> values_{};
  bool high_ = true;
};

// Version 2 contexts from (number of returns, return number), 3 bits each.
extern const uint8_t kReturnMap8[8][8];
extern const uint8_t kReturnLevel8[8][8];
// Version 3: the 6-context map and 8-level table of the 1.4 description.
extern const uint8_t kReturnMap6[16][16];
extern const uint8_t kReturnLevel8Ctx[16][16];

// --- GPS time (GPSTIME11 v2, and POINT14 v3's GPS layer) --------------------

// GPS times are coded as 64-bit integers: deltas predicted as a multiple of
// the last delta, in up to four sequences (interleaved flight lines).
template <class C>
class GpsTimeCodec {
 public:
  static constexpr int32_t kMulti = 500;
  static constexpr int32_t kMultiMinus = -10;

  // Version 2 has an "unchanged" symbol (511) and codes a new sequence as
  // 512 and switches as 513-515 (and 0 / 1 / 2 / 3-5 after a zero delta);
  // version 3 signals unchanged times in the XY layer, so 511 / 512-514
  // (and 0 / 1 / 2-4).
  GpsTimeCodec(bool v3, uint64_t first)
      : v3_(v3),
        code_full_(v3 ? 511 : 512),
        multi_model_(v3 ? 515 : 516),
        zero_diff_model_(v3 ? 5 : 6),
        ic_(32, 9) {
    last_time_[0] = first;
  }

  // True once a stream switched sequences twice in a row, which no encoder
  // does (a switch goes to a sequence the time is near): damaged data.
  bool damaged() const { return damaged_; }

  uint64_t Code(C& c, uint64_t target) {
    for (int switches = 0;; ++switches) {
      if (switches > 1) {
        damaged_ = true;
        return last_time_[last_];
      }
      uint64_t& last_time = last_time_[last_];
      int32_t& last_diff = last_diff_[last_];
      [[maybe_unused]] const int64_t diff64 = static_cast<int64_t>(target - last_time);
      [[maybe_unused]] const bool fits = diff64 == static_cast<int32_t>(diff64);
      if (last_diff == 0) {
        const uint32_t fits_code = v3_ ? 0 : 1;
        const uint32_t full_code = fits_code + 1;
        uint32_t symbol = 0;
        if constexpr (C::kEncoding) {
          if (!v3_ && target == last_time) {
            symbol = 0;
          } else if (fits) {
            symbol = fits_code;
          } else {
            const int other = OtherSequence(target);
            symbol = other > 0 ? full_code + static_cast<uint32_t>(other) : full_code;
          }
        }
        symbol = c.Symbol(zero_diff_model_, symbol);
        if (!v3_ && symbol == 0) return last_time;
        if (symbol == fits_code) {
          last_diff = c.Int(ic_, 0, static_cast<int32_t>(diff64), 0);
          last_time += static_cast<uint64_t>(static_cast<int64_t>(last_diff));
          extreme_counter_[last_] = 0;
          return last_time;
        }
        if (symbol == full_code) return NewSequence(c, target);
        last_ = (last_ + symbol - full_code) & 3;
        continue;
      }
      uint32_t symbol = 0;
      if constexpr (C::kEncoding) symbol = ChooseMulti(target, last_time, last_diff, diff64, fits);
      symbol = c.Symbol(multi_model_, symbol);
      if (symbol == 1) {
        const int32_t diff = c.Int(ic_, last_diff, static_cast<int32_t>(diff64), 1);
        last_time += static_cast<uint64_t>(static_cast<int64_t>(diff));
        extreme_counter_[last_] = 0;
        return last_time;
      }
      if (!v3_ && symbol == 511) return last_time;  // unchanged
      if (symbol < 511) {
        int32_t diff;
        const int32_t real = static_cast<int32_t>(diff64);
        if (symbol == 0) {
          diff = c.Int(ic_, 0, real, 7);
          CountExtreme(diff);
        } else if (symbol < static_cast<uint32_t>(kMulti)) {
          const int32_t multi = static_cast<int32_t>(symbol);
          diff = c.Int(ic_, WrapMul(multi, last_diff), real, multi < 10 ? 2 : 3);
        } else if (symbol == static_cast<uint32_t>(kMulti)) {
          diff = c.Int(ic_, WrapMul(kMulti, last_diff), real, 4);
          CountExtreme(diff);
        } else {
          const int32_t multi = kMulti - static_cast<int32_t>(symbol);
          if (multi > kMultiMinus) {
            diff = c.Int(ic_, WrapMul(multi, last_diff), real, 5);
          } else {
            diff = c.Int(ic_, WrapMul(kMultiMinus, last_diff), real, 6);
            CountExtreme(diff);
          }
        }
        last_time_[last_] += static_cast<uint64_t>(static_cast<int64_t>(diff));
        return last_time_[last_];
      }
      if (symbol == code_full_) return NewSequence(c, target);
      last_ = (last_ + symbol - code_full_) & 3;
    }
  }

 private:
  void CountExtreme(int32_t diff) {
    if (++extreme_counter_[last_] > 3) {
      last_diff_[last_] = diff;
      extreme_counter_[last_] = 0;
    }
  }

  uint64_t NewSequence(C& c, uint64_t target) {
    next_ = (next_ + 1) & 3;
    const int32_t high = c.Int(ic_, static_cast<int32_t>(last_time_[last_] >> 32),
                               static_cast<int32_t>(target >> 32), 8);
    const uint32_t low = c.Raw32(static_cast<uint32_t>(target));
    last_time_[next_] = (static_cast<uint64_t>(static_cast<uint32_t>(high)) << 32) | low;
    last_ = next_;
    last_diff_[last_] = 0;
    extreme_counter_[last_] = 0;
    return last_time_[last_];
  }

  // Encoding: the other sequence (1-3 ahead of last_) a 32-bit delta
  // reaches, or 0.
  int OtherSequence(uint64_t target) const {
    for (int i = 1; i < 4; ++i) {
      const int64_t diff = static_cast<int64_t>(target - last_time_[(last_ + i) & 3]);
      if (diff == static_cast<int32_t>(diff)) return i;
    }
    return 0;
  }

  uint32_t ChooseMulti(uint64_t target, uint64_t last_time, int32_t last_diff, int64_t diff64,
                       bool fits) const {
    if (!v3_ && target == last_time) return 511;
    if (!fits) {
      const int other = OtherSequence(target);
      return other > 0 ? code_full_ + static_cast<uint32_t>(other) : code_full_;
    }
    const double ratio = static_cast<double>(static_cast<int32_t>(diff64)) / last_diff;
    const double rounded = std::round(ratio);
    if (rounded == 1) return 1;
    if (rounded >= kMulti) return kMulti;
    if (rounded > 1) return static_cast<uint32_t>(rounded);
    if (rounded <= kMultiMinus) return kMulti - kMultiMinus;
    if (rounded < 0) return static_cast<uint32_t>(kMulti - static_cast<int32_t>(rounded));
    return 0;
  }

  bool v3_;
  bool damaged_ = false;
  uint32_t code_full_;
  SymbolModel multi_model_;
  SymbolModel zero_diff_model_;
  IntegerModel ic_;
  uint32_t last_ = 0;
  uint32_t next_ = 0;
  std::array<uint64_t, 4> last_time_{};
  std::array<int32_t, 4> last_diff_{};
  std::array<int32_t, 4> extreme_counter_{};
};

// --- RGB (RGB12 v2; RGB14 v3 per scanner channel) and NIR -------------------

// Six bytes, each coded as a difference to the last point's; G and B
// predicted from R's change; one flag for grey (R = G = B).
template <class C>
class RgbCodec {
 public:
  explicit RgbCodec(const uint8_t* first, size_t /*bytes: always 6*/ = 6) {
    std::memcpy(last_.data(), first, 6);
  }

  void Code(C& c, uint8_t* record) { CodeWith(c, record, last_.data()); }

  // Codes against `last_bytes` (6) and updates them; the layered format
  // sometimes predicts from another scanner channel's values (PerChannel).
  void CodeWith(C& c, uint8_t* record, uint8_t* last_bytes) {
    uint16_t last[3], now[3] = {0, 0, 0};
    for (int i = 0; i < 3; ++i) last[i] = LoadLe<uint16_t>(last_bytes + 2 * i);
    uint32_t used = 0;
    if constexpr (C::kEncoding) {
      for (int i = 0; i < 3; ++i) now[i] = LoadLe<uint16_t>(record + 2 * i);
      for (int i = 0; i < 3; ++i) {
        used |= static_cast<uint32_t>((last[i] & 0xFF) != (now[i] & 0xFF)) << (2 * i);
        used |= static_cast<uint32_t>((last[i] >> 8) != (now[i] >> 8)) << (2 * i + 1);
      }
      used |= static_cast<uint32_t>(now[0] != now[1] || now[0] != now[2]) << 6;
    }
    used = c.Symbol(byte_used_, used);
    uint32_t out[3];
    out[0] = CodeByte(c, used & 1, diff_[0], last[0] & 0xFF, now[0] & 0xFF);
    out[0] |= CodeByte(c, used & 2, diff_[1], last[0] >> 8, now[0] >> 8) << 8;
    if (used & 64) {
      int32_t diff = static_cast<int32_t>(out[0] & 0xFF) - (last[0] & 0xFF);
      out[1] = CodeByte(c, used & 4, diff_[2], ClampByte(diff + (last[1] & 0xFF)), now[1] & 0xFF,
                        last[1] & 0xFF);
      if (used & 16) {
        diff = (diff + (static_cast<int32_t>(out[1] & 0xFF) - (last[1] & 0xFF))) / 2;
      }
      out[2] = CodeByte(c, used & 16, diff_[4], ClampByte(diff + (last[2] & 0xFF)), now[2] & 0xFF,
                        last[2] & 0xFF);
      diff = static_cast<int32_t>(out[0] >> 8) - (last[0] >> 8);
      out[1] |= CodeByte(c, used & 8, diff_[3], ClampByte(diff + (last[1] >> 8)), now[1] >> 8,
                         last[1] >> 8)
                << 8;
      if (used & 32) diff = (diff + (static_cast<int32_t>(out[1] >> 8) - (last[1] >> 8))) / 2;
      out[2] |= CodeByte(c, used & 32, diff_[5], ClampByte(diff + (last[2] >> 8)), now[2] >> 8,
                         last[2] >> 8)
                << 8;
    } else {
      out[1] = out[2] = out[0];
    }
    for (int i = 0; i < 3; ++i)
      StoreLe<uint16_t>(last_bytes + 2 * i, static_cast<uint16_t>(out[i]));
    if constexpr (!C::kEncoding) std::memcpy(record, last_bytes, 6);
  }

  uint8_t* last() { return last_.data(); }

 private:
  // A byte coded as a difference to `prediction` when `changed`, else
  // `unchanged` (the last point's byte).
  static uint32_t CodeByte(C& c, uint32_t changed, SymbolModel& model, uint32_t prediction,
                           uint32_t target, uint32_t unchanged) {
    if (!changed) return unchanged;
    const uint32_t corr = c.Symbol(model, (target - prediction) & 0xFF);
    return (corr + prediction) & 0xFF;
  }
  static uint32_t CodeByte(C& c, uint32_t changed, SymbolModel& model, uint32_t last,
                           uint32_t target) {
    return CodeByte(c, changed, model, last, target, last);
  }

  std::array<uint8_t, 6> last_;
  SymbolModel byte_used_{128};
  std::array<SymbolModel, 6> diff_{SymbolModel(256), SymbolModel(256), SymbolModel(256),
                                   SymbolModel(256), SymbolModel(256), SymbolModel(256)};
};

template <class C>
class NirCodec {
 public:
  explicit NirCodec(const uint8_t* first, size_t /*bytes: always 2*/ = 2) {
    std::memcpy(last_.data(), first, 2);
  }

  void CodeWith(C& c, uint8_t* record, uint8_t* last) {
    uint32_t target = 0, used = 0;
    if constexpr (C::kEncoding) {
      target = LoadLe<uint16_t>(record);
      used = static_cast<uint32_t>((target & 0xFF) != last[0]) |
             (static_cast<uint32_t>((target >> 8) != last[1]) << 1);
    }
    used = c.Symbol(bytes_used_, used);
    uint32_t low = last[0], high = last[1];
    if (used & 1) low = (c.Symbol(diff_low_, (target - low) & 0xFF) + low) & 0xFF;
    if (used & 2) high = (c.Symbol(diff_high_, ((target >> 8) - high) & 0xFF) + high) & 0xFF;
    last[0] = static_cast<uint8_t>(low);
    last[1] = static_cast<uint8_t>(high);
    if constexpr (!C::kEncoding) std::memcpy(record, last, 2);
  }

  uint8_t* last() { return last_.data(); }

 private:
  std::array<uint8_t, 2> last_;
  SymbolModel bytes_used_{4};
  SymbolModel diff_low_{256};
  SymbolModel diff_high_{256};
};

// "Extra bytes": each byte a difference to the last point's, own model.
template <class C>
class ExtraBytesCodec {
 public:
  ExtraBytesCodec(const uint8_t* first, size_t count) : last_(first, first + count) {
    models_.reserve(count);
    for (size_t i = 0; i < count; ++i) models_.emplace_back(256);
  }

  // Byte `i` only (the layered format codes each byte in its own layer).
  void CodeByteWith(C& c, size_t i, uint8_t* byte, uint8_t* last) {
    uint32_t diff = 0;
    if constexpr (C::kEncoding) diff = static_cast<uint8_t>(*byte - last[i]);
    last[i] = static_cast<uint8_t>(last[i] + c.Symbol(models_[i], diff));
    if constexpr (!C::kEncoding) *byte = last[i];
  }
  void Code(C& c, uint8_t* bytes) {
    for (size_t i = 0; i < last_.size(); ++i) CodeByteWith(c, i, bytes + i, last_.data());
  }
  uint8_t* last() { return last_.data(); }

 private:
  std::vector<uint8_t> last_;
  std::vector<SymbolModel> models_;
};

// --- POINT10 v2 (formats 0-5) ----------------------------------------------

template <class C>
class Point10Codec {
 public:
  explicit Point10Codec(const uint8_t* first) {
    std::memcpy(last_.data(), first, 20);
    // The "unchanged intensity" of the second point is last_intensity_[m]
    // (0), so the first point's must not leak through.
    StoreLe<uint16_t>(last_.data() + 12, 0);
  }

  void Code(C& c, uint8_t* record) {
    uint8_t* last = last_.data();
    uint32_t changed = 0;
    if constexpr (C::kEncoding) {
      const uint32_t r = record[14] & 7, n = (record[14] >> 3) & 7;
      const uint32_t m = kReturnMap8[n][r];
      changed = (static_cast<uint32_t>(last[14] != record[14]) << 5) |
                (static_cast<uint32_t>(last_intensity_[m] != LoadLe<uint16_t>(record + 12)) << 4) |
                (static_cast<uint32_t>(last[15] != record[15]) << 3) |
                (static_cast<uint32_t>(last[16] != record[16]) << 2) |
                (static_cast<uint32_t>(last[17] != record[17]) << 1) |
                static_cast<uint32_t>(LoadLe<uint16_t>(last + 18) != LoadLe<uint16_t>(record + 18));
    }
    changed = c.Symbol(changed_values_, changed);
    uint32_t r = last[14] & 7, n = (last[14] >> 3) & 7;
    uint32_t m = kReturnMap8[n][r], l = kReturnLevel8[n][r];
    if (changed != 0) {
      if (changed & 32) {
        last[14] = static_cast<uint8_t>(c.Symbol(bit_byte_[last[14]], record[14]));
        r = last[14] & 7;
        n = (last[14] >> 3) & 7;
        m = kReturnMap8[n][r];
        l = kReturnLevel8[n][r];
      }
      if (changed & 16) {
        last_intensity_[m] = static_cast<uint16_t>(
            c.Int(ic_intensity_, last_intensity_[m], LoadLe<uint16_t>(record + 12), m < 3 ? m : 3));
      }
      StoreLe<uint16_t>(last + 12, last_intensity_[m]);
      if (changed & 8)
        last[15] = static_cast<uint8_t>(c.Symbol(classification_[last[15]], record[15]));
      if (changed & 4) {
        const uint32_t diff =
            c.Symbol(scan_angle_[(last[14] >> 6) & 1], static_cast<uint8_t>(record[16] - last[16]));
        last[16] = static_cast<uint8_t>(diff + last[16]);
      }
      if (changed & 2) last[17] = static_cast<uint8_t>(c.Symbol(user_data_[last[17]], record[17]));
      if (changed & 1) {
        StoreLe<uint16_t>(last + 18,
                          static_cast<uint16_t>(c.Int(ic_point_source_, LoadLe<uint16_t>(last + 18),
                                                      LoadLe<uint16_t>(record + 18), 0)));
      }
    }
    const bool single = n == 1;
    int32_t x = LoadLe<int32_t>(last), y = LoadLe<int32_t>(last + 4);
    const int32_t dx = c.Int(ic_dx_, x_median_[m].Get(),
                             C::kEncoding ? WrapSub(LoadLe<int32_t>(record), x) : 0, single);
    x = WrapAdd(x, dx);
    x_median_[m].Add(dx);
    uint32_t k = ic_dx_.k;
    const int32_t dy = c.Int(ic_dy_, y_median_[m].Get(),
                             C::kEncoding ? WrapSub(LoadLe<int32_t>(record + 4), y) : 0,
                             single + (k < 20 ? k & ~1u : 20));
    y = WrapAdd(y, dy);
    y_median_[m].Add(dy);
    k = (ic_dx_.k + ic_dy_.k) / 2;
    last_height_[l] = c.Int(ic_z_, last_height_[l], C::kEncoding ? LoadLe<int32_t>(record + 8) : 0,
                            single + (k < 18 ? k & ~1u : 18));
    StoreLe(last, x);
    StoreLe(last + 4, y);
    StoreLe(last + 8, last_height_[l]);
    if constexpr (!C::kEncoding) std::memcpy(record, last, 20);
  }

 private:
  std::array<uint8_t, 20> last_;
  std::array<uint16_t, 16> last_intensity_{};
  std::array<Median5, 16> x_median_{};
  std::array<Median5, 16> y_median_{};
  std::array<int32_t, 8> last_height_{};
  SymbolModel changed_values_{64};
  IntegerModel ic_intensity_{16, 4};
  std::array<SymbolModel, 2> scan_angle_{SymbolModel(256), SymbolModel(256)};
  IntegerModel ic_point_source_{16};
  LazySymbolModels bit_byte_{256, 256};
  LazySymbolModels classification_{256, 256};
  LazySymbolModels user_data_{256, 256};
  IntegerModel ic_dx_{32, 2};
  IntegerModel ic_dy_{32, 22};
  IntegerModel ic_z_{32, 20};
};

}  // namespace pb::laz
