// The entropy coder of LAZ: adaptive binary and multi-symbol models, the
// arithmetic decoder and the "integer compressor" (a corrector coded as its
// bit length k, then the k bits, relative to a prediction). Written from
// the LASzip format description ("LASzip: lossless compression of LiDAR
// data", M. Isenburg, 2013, section 3; LASzip/design/specification.rst for
// the layered 1.4 items) and Amir Said's "Introduction to arithmetic coding"
// (2003), whose 32-bit coder with 15-bit (multi-symbol) and 13-bit (binary)
// probabilities LAZ uses; the adaptation schedule (counts halved past 2^15 /
// 2^13, update periods growing by 5/4 up to a cap) is part of the format.
//
// Decoding must reproduce the encoder's model updates bit for bit, so every
// constant here is part of the file format, not a tuning choice.
//
// The decoder never reads outside the bytes it was given: past the end it
// reads zeros and counts them (`overrun_bytes`); a stream whose coder state
// becomes impossible (value >= length) sets `corrupt`. Callers turn either
// into an error naming the chunk and the point.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace pb::laz {

constexpr uint32_t kMinLength = 0x01000000u;  // renormalize below this
constexpr uint32_t kMaxLength = 0xFFFFFFFFu;
constexpr uint32_t kBitLengthShift = 13;  // binary models: 13-bit probabilities
constexpr uint32_t kBitMaxCount = 1u << kBitLengthShift;
constexpr uint32_t kSymbolLengthShift = 15;  // multi-symbol models: 15 bits
constexpr uint32_t kSymbolMaxCount = 1u << kSymbolLengthShift;

// An adaptive model of one binary decision.
struct BitModel {
  uint32_t bit_0_count = 1;
  uint32_t bit_count = 2;
  uint32_t bit_0_prob = 1u << (kBitLengthShift - 1);
  uint32_t update_cycle = 4;
  uint32_t bits_until_update = 4;

  void Update();
};

// An adaptive model of a symbol in [0, symbols). Models of more than 16
// symbols keep a lookup table from the scaled value to a first guess.
class SymbolModel {
 public:
  explicit SymbolModel(uint32_t symbols);

  uint32_t symbols() const { return symbols_; }
  void Update();

  // The coder's view; public so that the decoder below and the test
  // encoder share one definition of the model.
  uint32_t symbols_;
  uint32_t last_symbol_;
  uint32_t table_size_ = 0;
  uint32_t table_shift_ = 0;
  uint32_t total_count_ = 0;
  uint32_t update_cycle_;
  uint32_t symbols_until_update_;
  std::vector<uint32_t> distribution_;  // symbols_ entries, 15-bit scaled CDF
  std::vector<uint32_t> symbol_count_;
  std::vector<uint32_t> decoder_table_;  // table_size_ + 2 entries, or empty
};

// Models created on first use: LAZ makes many context-indexed models (e.g.
// one per previous classification) that most files never touch.
class LazySymbolModels {
 public:
  LazySymbolModels(size_t contexts, uint32_t symbols) : symbols_(symbols), models_(contexts) {}
  SymbolModel& operator[](size_t context) {
    std::unique_ptr<SymbolModel>& model = models_[context];
    if (!model) model = std::make_unique<SymbolModel>(symbols_);
    return *model;
  }

 private:
  uint32_t symbols_;
  std::vector<std::unique_ptr<SymbolModel>> models_;
};

// The integer compressor's models: an integer is coded as its difference
// ("corrector") to a prediction, wrapped into `bits` bits; the corrector's
// bit length k is a symbol of a per-context model, then its value within
// that length is coded with a per-k model (and raw bits past bits_high).
struct IntegerModel {
  explicit IntegerModel(uint32_t bits = 16, uint32_t contexts = 1, uint32_t bits_high = 8);

  uint32_t corr_bits;
  uint32_t corr_range;  // 0 = 32 bits, no wrapping
  int32_t corr_min;
  int32_t corr_max;
  uint32_t bits_high;
  std::vector<SymbolModel> k_models;    // per context: k in [0, corr_bits]
  BitModel corrector_0;                 // k = 0: the corrector is 0 or 1
  std::vector<SymbolModel> correctors;  // [k - 1] for k in [1, corr_bits]
  uint32_t k = 0;                       // the last corrector's bit length; later contexts use it
};

// Reads one arithmetic-coded stream held in [begin, end).
class ArithmeticDecoder {
 public:
  void Init(const uint8_t* begin, const uint8_t* end) {
    next_ = begin;
    end_ = end;
    overrun_bytes_ = 0;
    corrupt_ = false;
    length_ = kMaxLength;
    value_ = 0;
    for (int i = 0; i < 4; ++i) value_ = (value_ << 8) | NextByte();
  }

  uint32_t DecodeBit(BitModel& m) {
    const uint32_t x = m.bit_0_prob * (length_ >> kBitLengthShift);
    const uint32_t bit = value_ >= x;
    if (bit == 0) {
      length_ = x;
      ++m.bit_0_count;
    } else {
      value_ -= x;
      length_ -= x;
    }
    if (length_ < kMinLength) Renormalize();
    if (--m.bits_until_update == 0) m.Update();
    return bit;
  }

  uint32_t DecodeSymbol(SymbolModel& m) {
    if (value_ >= length_) Corrupt();
    uint32_t symbol;
    uint32_t x;
    uint32_t y = length_;
    if (!m.decoder_table_.empty()) {
      length_ >>= kSymbolLengthShift;
      const uint32_t scaled = value_ / length_;
      const uint32_t t = scaled >> m.table_shift_;
      symbol = m.decoder_table_[t];
      uint32_t n = m.decoder_table_[t + 1] + 1;
      while (n > symbol + 1) {  // bisect within the table's bracket
        const uint32_t k = (symbol + n) >> 1;
        if (m.distribution_[k] > scaled) {
          n = k;
        } else {
          symbol = k;
        }
      }
      x = m.distribution_[symbol] * length_;
      if (symbol != m.last_symbol_) y = m.distribution_[symbol + 1] * length_;
    } else {
      x = symbol = 0;
      length_ >>= kSymbolLengthShift;
      uint32_t n = m.symbols_;
      uint32_t k = n >> 1;
      do {
        const uint32_t z = length_ * m.distribution_[k];
        if (z > value_) {
          n = k;
          y = z;
        } else {
          symbol = k;
          x = z;
        }
      } while ((k = (symbol + n) >> 1) != symbol);
    }
    value_ -= x;
    length_ = y - x;
    if (length_ < kMinLength) Renormalize();
    ++m.symbol_count_[symbol];
    if (--m.symbols_until_update_ == 0) m.Update();
    return symbol;
  }

  // `bits` raw bits (1..32), coded with a flat distribution.
  uint32_t ReadBits(uint32_t bits) {
    if (bits > 19) {
      const uint32_t low = ReadShort();
      return (ReadBits(bits - 16) << 16) | low;
    }
    return ReadFlat(bits);
  }
  uint32_t ReadShort() { return ReadFlat(16); }
  uint32_t ReadInt() {
    const uint32_t low = ReadShort();
    return (ReadShort() << 16) | low;
  }

  // The integer compressor: `prediction` + the decoded corrector, wrapped.
  int32_t DecodeInt(IntegerModel& ic, int32_t prediction, uint32_t context) {
    const int32_t corrector = DecodeCorrector(ic, ic.k_models[context]);
    uint32_t real = static_cast<uint32_t>(prediction) + static_cast<uint32_t>(corrector);
    if (ic.corr_range != 0) {
      if (static_cast<int32_t>(real) < 0) {
        real += ic.corr_range;
      } else if (real >= ic.corr_range) {
        real -= ic.corr_range;
      }
    }
    return static_cast<int32_t>(real);
  }

  size_t overrun_bytes() const { return overrun_bytes_; }
  bool corrupt() const { return corrupt_; }

 private:
  uint8_t NextByte() {
    if (next_ < end_) return *next_++;
    ++overrun_bytes_;
    return 0;
  }

  void Renormalize() {
    if (length_ == 0) {  // only damaged data gets here; shifting 0 never ends
      Corrupt();
      length_ = kMaxLength;
      value_ = 0;
      return;
    }
    do {
      value_ = (value_ << 8) | NextByte();
    } while ((length_ <<= 8) < kMinLength);
  }

  // Keeps a damaged stream's state possible (value < length) so that no
  // table lookup leaves its table; the caller reports the damage.
  void Corrupt() {
    corrupt_ = true;
    value_ = length_ - 1;
  }

  uint32_t ReadFlat(uint32_t bits) {
    length_ >>= bits;
    uint32_t symbol = value_ / length_;
    if (symbol >> bits) {
      Corrupt();
      symbol = value_ / length_;
    }
    value_ -= length_ * symbol;
    if (length_ < kMinLength) Renormalize();
    return symbol;
  }

  int32_t DecodeCorrector(IntegerModel& ic, SymbolModel& k_model) {
    const uint32_t k = DecodeSymbol(k_model);
    ic.k = k;
    if (k == 0) return static_cast<int32_t>(DecodeBit(ic.corrector_0));
    if (k >= 32) return ic.corr_min;
    uint32_t c;
    if (k <= ic.bits_high) {
      c = DecodeSymbol(ic.correctors[k - 1]);
    } else {
      const uint32_t low_bits = k - ic.bits_high;
      c = DecodeSymbol(ic.correctors[k - 1]);
      c = (c << low_bits) | ReadBits(low_bits);
    }
    // c in [0, 2^k): the upper half maps to [2^(k-1) + 1, 2^k], the lower
    // to [-(2^k - 1), -2^(k-1)].
    if (c >= (1u << (k - 1))) return static_cast<int32_t>(c + 1);
    return static_cast<int32_t>(c - ((1u << k) - 1));
  }

  const uint8_t* next_ = nullptr;
  const uint8_t* end_ = nullptr;
  size_t overrun_bytes_ = 0;
  bool corrupt_ = false;
  uint32_t value_ = 0;
  uint32_t length_ = kMaxLength;
};

// The coder interface the item codecs (laz_items.h) are written against,
// decoding side: each call takes the value an encoder would code and
// returns the value decoded (the argument is ignored). The test encoder
// provides the same calls, so one description of each item serves both.
class DecodingCoder {
 public:
  static constexpr bool kEncoding = false;

  void Init(const uint8_t* begin, const uint8_t* end) { decoder_.Init(begin, end); }
  uint32_t Bit(BitModel& m, uint32_t) { return decoder_.DecodeBit(m); }
  uint32_t Symbol(SymbolModel& m, uint32_t) { return decoder_.DecodeSymbol(m); }
  uint32_t Raw32(uint32_t) { return decoder_.ReadInt(); }
  int32_t Int(IntegerModel& ic, int32_t prediction, int32_t, uint32_t context) {
    return decoder_.DecodeInt(ic, prediction, context);
  }
  const ArithmeticDecoder& decoder() const { return decoder_; }

 private:
  ArithmeticDecoder decoder_;
};

}  // namespace pb::laz
