// The window's selections off its thread (selection_worker.h, newest_request_worker.h): each finished selection is the
// one the synchronous path gives for the same regions, the newest request wins over those still waiting, and a failure
// comes back as an error, not an exception on the window's thread.
#include <gtest/gtest.h>

#include "converter/convert/convert.h"
#include "converter/synth/synth.h"
#include "tests/test_support.h"
#include "viewer/app/selection_worker.h"

namespace vxl::app {
namespace {

SelectionCriteria sphere_at(double x, double r) {
  SelectionCriteria c;
  c.include.push_back(parse_region(std::to_string(x) + ",-18,10," + std::to_string(r)));
  return c;
}

class SelectionWorkerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    SynthSettings s;
    s.streamlines = 2000;
    ConvertSettings c;
    c.threads = 2;
    convert_tractogram(synthesize_tractogram(s), dir.file("s.vxl"), c);
    file.emplace(VxlFile::open(dir.file("s.vxl")));
  }
  test::ScratchDir dir;
  std::optional<VxlFile> file;
};

TEST_F(SelectionWorkerTest, EachSelectionIsTheSynchronousOne) {
  const std::vector<const VxlFile*> files = {&*file};
  SelectionWorker worker(files, std::make_shared<VoxelVoxlinesCache>(files));
  for (int i = 0; i < 4; ++i) {
    const SelectionCriteria c = sphere_at(-30.0 + 20 * i, 12);
    worker.request(i + 1, c);
    const std::optional<SelectionWorker::Done> done = worker.poll(true);
    ASSERT_TRUE(done.has_value());
    ASSERT_TRUE(done->result.has_value()) << done->error;
    EXPECT_EQ(done->number, std::uint64_t(i + 1));
    const SceneSelection expected = select_in_scene(files, c);
    EXPECT_EQ(done->result->kept, expected.kept);
    EXPECT_EQ(done->result->streamlines_per_region, expected.streamlines_per_region);
    EXPECT_FALSE(worker.busy());
  }
}

TEST_F(SelectionWorkerTest, TheNewestRequestWinsAndNothingIsLeftRunning) {
  const std::vector<const VxlFile*> files = {&*file};
  SelectionWorker worker(files, std::make_shared<VoxelVoxlinesCache>(files));
  // Requests faster than the worker runs them: the first starts at once, each later one replaces the one
  // waiting, so at most the first and the last run; the newest result is the last request's.
  for (int i = 0; i < 20; ++i) worker.request(i + 1, sphere_at(-40.0 + 4 * i, 10));
  const std::optional<SelectionWorker::Done> done = worker.poll(true);
  ASSERT_TRUE(done.has_value());
  EXPECT_EQ(done->number, 20u);
  EXPECT_EQ(done->result->kept, select_in_scene(files, sphere_at(-40.0 + 4 * 19, 10)).kept);
  EXPECT_FALSE(worker.busy());
  EXPECT_FALSE(worker.poll(true).has_value());  // nothing new since
}

TEST_F(SelectionWorkerTest, AFailureComesBackAsAnError) {
  const std::vector<const VxlFile*> files = {&*file};
  SelectionWorker worker(files, std::make_shared<VoxelVoxlinesCache>(files));
  SelectionCriteria c = sphere_at(0, 10);
  c.min_length = 100, c.max_length = 50;  // refused by the selection
  worker.request(1, c);
  const std::optional<SelectionWorker::Done> done = worker.poll(true);
  ASSERT_TRUE(done.has_value());
  EXPECT_FALSE(done->result.has_value());
  EXPECT_NE(done->error.find("minimum length"), std::string::npos) << done->error;
}

}  // namespace
}  // namespace vxl::app
