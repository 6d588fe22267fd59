// main() of every viosfm test binary. Exit codes: 0 all run tests passed
// (some may have been skipped), 1 a test failed, 77 every test was skipped
// (ctest reports that binary as skipped: SKIP_RETURN_CODE 77).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

int main(int argc, char** argv) {
  ::testing::InitGoogleMock(&argc, argv);
  const int status = RUN_ALL_TESTS();
  if (status != 0) return status;
  const ::testing::UnitTest& unit = *::testing::UnitTest::GetInstance();
  if (unit.test_to_run_count() > 0 && unit.skipped_test_count() == unit.test_to_run_count()) {
    return 77;
  }
  return 0;
}
