// The fuzz targets' seeds and every input that once made a fuzzer fail, replayed through the
// targets (tests/fuzz/corpus/<target>/, one input per file): the fuzzers' oracle, in the suite.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "../fuzz/fuzz_targets.h"

namespace modal_deform {
namespace {

using Target = void (*)(const std::uint8_t*, std::size_t);

void replay(const std::string& name, Target target) {
  const std::filesystem::path folder = std::filesystem::path(MODAL_DEFORM_FUZZ_CORPUS) / name;
  ASSERT_TRUE(std::filesystem::is_directory(folder)) << folder;
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    std::ifstream file(entry.path(), std::ios::binary);
    const std::vector<char> bytes{std::istreambuf_iterator<char>(file),
                                  std::istreambuf_iterator<char>()};
    EXPECT_NO_THROW(target(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()))
        << entry.path();
    ++count;
  }
  EXPECT_GT(count, 0) << "no inputs in " << folder;
}

TEST(FuzzCorpus, MeshEntryPoints) { replay("mesh_entry_points", fuzz::mesh_entry_points); }
TEST(FuzzCorpus, BakeAndPose) { replay("bake_and_pose", fuzz::bake_and_pose); }
TEST(FuzzCorpus, StoredBasis) { replay("stored_basis", fuzz::stored_basis); }

}  // namespace
}  // namespace modal_deform
