#include "stages/geometry/core/buffered_input.h"

#include "stages/geometry/testing/test_data.h"
#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>


namespace pb {
namespace {

constexpr size_t kMiB = BufferedInput::kBufferBytes;

class BufferedInputTest : public pb::testing::TempDirTest {
 protected:
};

TEST_F(BufferedInputTest, LfCrlfAndLoneCr) {
  BufferedInput in;
  ASSERT_TRUE(in.Open(Write("a.txt", "unix\nwindows\r\n\r\n\nold\rmac\nlast"), "a test file",
                      nullptr).ok());
  std::string_view line;
  ASSERT_TRUE(in.ReadLine(&line));
  EXPECT_EQ(line, "unix");
  EXPECT_EQ(in.offset(), 5u);
  ASSERT_TRUE(in.ReadLine(&line));
  EXPECT_EQ(line, "windows");
  EXPECT_EQ(in.offset(), 14u);
  ASSERT_TRUE(in.ReadLine(&line));
  EXPECT_EQ(line, "");  // "\r\n"
  ASSERT_TRUE(in.ReadLine(&line));
  EXPECT_EQ(line, "");  // "\n"
  ASSERT_TRUE(in.ReadLine(&line));
  EXPECT_EQ(line, "old\rmac");  // a lone CR does not end a line
  std::string copy;
  ASSERT_TRUE(in.ReadLine(&copy));
  EXPECT_EQ(copy, "last");  // no final LF
  EXPECT_EQ(in.line_number(), 6);
  EXPECT_EQ(in.offset(), in.size());
  EXPECT_FALSE(in.ReadLine(&line));
  EXPECT_TRUE(in.error().ok());
  EXPECT_FALSE(in.line_too_long());
}

TEST_F(BufferedInputTest, LineLongerThanTheMaximum) {
  BufferedInput in(16);
  // 16 bytes with the CR, 16 without: both fit; 17 does not.
  ASSERT_TRUE(in.Open(Write("a.txt", "0123456789abcde\r\n0123456789abcdef\n" +
                                         std::string(17, 'x') + "\nok\n"),
                      "a test file", nullptr).ok());
  std::string_view line;
  ASSERT_TRUE(in.ReadLine(&line));
  EXPECT_EQ(line, "0123456789abcde");
  ASSERT_TRUE(in.ReadLine(&line));
  EXPECT_EQ(line, "0123456789abcdef");
  EXPECT_FALSE(in.ReadLine(&line));
  EXPECT_TRUE(in.line_too_long());
  EXPECT_TRUE(in.error().ok());
  EXPECT_EQ(in.line_number(), 2);  // the caller reports line 3
}

TEST_F(BufferedInputTest, LongLinesAcrossBufferFills) {
  // "a\n", then a line of exactly 1 MiB that straddles the first fill, then
  // one byte more than that.
  const std::string exact(kMiB, 'e');
  const std::string over(kMiB + 1, 'o');
  BufferedInput in;  // max 1 MiB
  ASSERT_TRUE(in.Open(Write("a.txt", "a\n" + exact + "\n" + over + "\n"), "a test file",
                      nullptr).ok());
  std::string_view line;
  ASSERT_TRUE(in.ReadLine(&line));
  EXPECT_EQ(line, "a");
  ASSERT_TRUE(in.ReadLine(&line));
  EXPECT_EQ(line.size(), kMiB);
  EXPECT_EQ(line, exact);
  EXPECT_EQ(in.offset(), 2 + kMiB + 1);
  EXPECT_FALSE(in.ReadLine(&line));
  EXPECT_TRUE(in.line_too_long());
}

TEST_F(BufferedInputTest, ManyLinesAcrossBufferFills) {
  std::string text;
  for (int i = 0; i < 300000; ++i) text += "line " + std::to_string(i) + (i % 2 ? "\r\n" : "\n");
  ASSERT_GT(text.size(), 2 * kMiB);
  BufferedInput in(64);
  ASSERT_TRUE(in.Open(Write("a.txt", text), "a test file", nullptr).ok());
  std::string_view line;
  int count = 0;
  while (in.ReadLine(&line)) {
    ASSERT_EQ(line, "line " + std::to_string(count)) << "line " << count + 1;
    ++count;
  }
  EXPECT_EQ(count, 300000);
  EXPECT_EQ(in.line_number(), 300000);
  EXPECT_FALSE(in.line_too_long());
  EXPECT_EQ(in.offset(), text.size());
}

// A 3.5 MiB file of bytes i % 251, read in 7-byte records: every fill
// boundary falls inside a record.
std::string Pattern(size_t n) {
  std::string bytes(n, '\0');
  for (size_t i = 0; i < n; ++i) bytes[i] = static_cast<char>(i % 251);
  return bytes;
}

TEST_F(BufferedInputTest, ReadsAcrossBufferBoundariesWithExactOffsets) {
  const size_t n = 3 * kMiB + kMiB / 2;
  BufferedInput in;
  ASSERT_TRUE(in.Open(Write("a.bin", Pattern(n)), "a test file", nullptr).ok());
  EXPECT_EQ(in.size(), n);
  uint8_t record[7];
  uint64_t records = 0;
  while (in.Read(record, sizeof record)) {
    const uint64_t start = records * 7;
    for (size_t k = 0; k < 7; ++k) ASSERT_EQ(record[k], (start + k) % 251) << "byte " << start + k;
    ++records;
    ASSERT_EQ(in.offset(), records * 7);
  }
  EXPECT_EQ(records, n / 7);
  EXPECT_EQ(in.offset(), n);  // the short last record was consumed
  EXPECT_EQ(in.remaining(), 0u);
  EXPECT_EQ(in.GetByte(), -1);
  EXPECT_TRUE(in.error().ok());
}

TEST_F(BufferedInputTest, ByteReadsSkipAndSeek) {
  const size_t n = 3 * kMiB;
  BufferedInput in;
  ASSERT_TRUE(in.Open(Write("a.bin", Pattern(n)), "a test file", nullptr).ok());
  EXPECT_EQ(in.GetByte(), 0);
  EXPECT_EQ(in.GetByte(), 1);
  EXPECT_EQ(in.Skip(8), 8u);  // inside the buffer
  EXPECT_EQ(in.offset(), 10u);
  EXPECT_EQ(in.GetByte(), 10);
  EXPECT_EQ(in.Skip(2 * kMiB), 2 * kMiB);  // past the buffer: a seek
  EXPECT_EQ(in.offset(), 11 + 2 * kMiB);
  EXPECT_EQ(in.GetByte(), static_cast<int>((11 + 2 * kMiB) % 251));
  ASSERT_TRUE(in.Seek(5));  // backwards, out of the buffer
  EXPECT_EQ(in.GetByte(), 5);
  char bytes[4];
  ASSERT_TRUE(in.Seek(n - 2));
  EXPECT_EQ(in.ReadUpTo(bytes, sizeof bytes), 2u);
  EXPECT_EQ(static_cast<uint8_t>(bytes[1]), (n - 1) % 251);
  ASSERT_TRUE(in.Seek(n - 3));
  EXPECT_EQ(in.Skip(10), 3u);  // clamped at the end
  EXPECT_EQ(in.offset(), n);
  EXPECT_TRUE(in.error().ok());
}

TEST_F(BufferedInputTest, ProgressReachesOne) {
  const size_t n = 3 * kMiB + 123;
  std::vector<double> fractions;
  const std::function<void(double)> progress = [&](double f) { fractions.push_back(f); };
  BufferedInput in;
  ASSERT_TRUE(in.Open(Write("a.bin", Pattern(n)), "a test file", &progress).ok());
  char record[1000];
  while (in.Read(record, sizeof record)) {
  }
  ASSERT_EQ(fractions.size(), 5u);  // one per 1 MiB fill, and the empty one at end of file
  EXPECT_DOUBLE_EQ(fractions[0], static_cast<double>(kMiB) / n);
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
}

TEST_F(BufferedInputTest, OpenErrorsNameThePath) {
  BufferedInput missing;
  const std::string absent = (dir_ / "absent.ply").string();
  const Status status = missing.Open(absent, "a PLY file", nullptr);
  EXPECT_EQ(status.code(), Status::Code::kNotFound);
  EXPECT_EQ(status.message(), absent + ": no such file");
  BufferedInput directory;
  EXPECT_EQ(directory.Open(dir_.string(), "a PLY file", nullptr).message(),
            dir_.string() + ": is a directory, not a PLY file");
}

}  // namespace
}  // namespace pb
