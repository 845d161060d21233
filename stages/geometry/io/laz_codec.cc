#include "stages/geometry/io/laz_codec.h"

namespace pb::laz {

void BitModel::Update() {
  if ((bit_count += update_cycle) > kBitMaxCount) {
    bit_count = (bit_count + 1) >> 1;
    bit_0_count = (bit_0_count + 1) >> 1;
    if (bit_0_count == bit_count) ++bit_count;
  }
  const uint32_t scale = 0x80000000u / bit_count;
  bit_0_prob = (bit_0_count * scale) >> (31 - kBitLengthShift);
  update_cycle = (5 * update_cycle) >> 2;
  if (update_cycle > 64) update_cycle = 64;
  bits_until_update = update_cycle;
}

SymbolModel::SymbolModel(uint32_t symbols)
    : symbols_(symbols),
      last_symbol_(symbols - 1),
      update_cycle_(symbols),
      symbols_until_update_(symbols),
      distribution_(symbols),
      symbol_count_(symbols, 1) {
  if (symbols > 16) {
    // The table only speeds up decoding (the distribution alone defines
    // the code); LASzip sizes it at about symbols / 4 entries, we at about
    // symbols, which saves bisection steps for a larger Update(). At most
    // 2^9 entries: value / (length >> 15) can exceed 2^15 by up to 63
    // (length >= 2^24), which a shift of at least 6 keeps inside the
    // table's one spare entry; a 516-symbol table of 2^10 read past its end.
    uint32_t table_bits = 5;
    while (symbols > (1u << table_bits) && table_bits < 9) ++table_bits;
    table_size_ = 1u << table_bits;
    table_shift_ = kSymbolLengthShift - table_bits;
    decoder_table_.resize(table_size_ + 2);
  }
  Update();
  update_cycle_ = symbols_until_update_ = (symbols + 6) >> 1;
}

void SymbolModel::Update() {
  if ((total_count_ += update_cycle_) > kSymbolMaxCount) {
    total_count_ = 0;
    for (uint32_t& count : symbol_count_) {
      count = (count + 1) >> 1;
      total_count_ += count;
    }
  }
  const uint32_t scale = 0x80000000u / total_count_;
  uint32_t sum = 0;
  if (decoder_table_.empty()) {
    for (uint32_t k = 0; k < symbols_; ++k) {
      distribution_[k] = (scale * sum) >> (31 - kSymbolLengthShift);
      sum += symbol_count_[k];
    }
  } else {
    uint32_t s = 0;
    for (uint32_t k = 0; k < symbols_; ++k) {
      distribution_[k] = (scale * sum) >> (31 - kSymbolLengthShift);
      sum += symbol_count_[k];
      const uint32_t w = distribution_[k] >> table_shift_;
      while (s < w) decoder_table_[++s] = k - 1;
    }
    decoder_table_[0] = 0;
    while (s <= table_size_) decoder_table_[++s] = symbols_ - 1;
  }
  update_cycle_ = (5 * update_cycle_) >> 2;
  const uint32_t max_cycle = (symbols_ + 6) << 3;
  if (update_cycle_ > max_cycle) update_cycle_ = max_cycle;
  symbols_until_update_ = update_cycle_;
}

IntegerModel::IntegerModel(uint32_t bits, uint32_t contexts, uint32_t bits_high_in)
    : bits_high(bits_high_in) {
  if (bits != 0 && bits < 32) {
    corr_bits = bits;
    corr_range = 1u << bits;
    corr_min = -static_cast<int32_t>(corr_range / 2);
    corr_max = corr_min + static_cast<int32_t>(corr_range) - 1;
  } else {
    corr_bits = 32;
    corr_range = 0;
    corr_min = INT32_MIN;
    corr_max = INT32_MAX;
  }
  k_models.reserve(contexts);
  for (uint32_t i = 0; i < contexts; ++i) k_models.emplace_back(corr_bits + 1);
  correctors.reserve(corr_bits);
  for (uint32_t i = 1; i <= corr_bits; ++i) {
    correctors.emplace_back(i <= bits_high ? 1u << i : 1u << bits_high);
  }
}

}  // namespace pb::laz
