#include "stages/geometry/io/scan_read.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <set>

#include "stages/geometry/testing/test_data.h"

namespace pb {
namespace {

using ::testing::HasSubstr;

TEST(ScanReadTest, FormatsByNameAndByExtension) {
  std::set<std::string_view> names;
  for (const ScanFormat& format : ScanFormats()) {
    EXPECT_TRUE(names.insert(format.name).second) << "two rows named " << format.name;
    EXPECT_NE(format.read, nullptr) << format.name;
  }
  EXPECT_EQ(names, (std::set<std::string_view>{"ply", "pcd", "xyz", "ptx", "e57", "las"}));
  EXPECT_EQ((*FindScanFormat("room.E57", "auto"))->name, "e57");
  EXPECT_EQ((*FindScanFormat("a/b.pts", "auto"))->name, "xyz");
  EXPECT_EQ((*FindScanFormat("scan.laz", "auto"))->name, "las");
  // A name wins over the extension.
  EXPECT_EQ((*FindScanFormat("points.dat", "xyz"))->name, "xyz");

  auto unknown_name = FindScanFormat("scan.ply", "obj");
  EXPECT_EQ(unknown_name.status().code(), Status::Code::kUnsupported);
  EXPECT_THAT(unknown_name.status().message(), HasSubstr("scan.ply: unknown format 'obj'"));
  EXPECT_THAT(unknown_name.status().message(), HasSubstr(SupportedScanFormats()));
  auto no_extension = FindScanFormat("dir/scan", "auto");
  EXPECT_THAT(no_extension.status().message(), HasSubstr("'dir/scan': no file extension"));
}

TEST(ScanReadTest, ReadScanDispatchesToTheFormatsReader) {
  testing::TempDir dir;
  const std::string path = dir.Write("grid.txt", "0 0 0\n1 0 0\n0 1 0\n");
  auto read = ReadScan(path, "auto", {});
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_EQ(read->points.size(), 3u);
  auto as_ply = ReadScan(path, "ply", {});
  EXPECT_FALSE(as_ply.ok());
  EXPECT_THAT(as_ply.status().message(), HasSubstr(path));
}

}  // namespace
}  // namespace pb
