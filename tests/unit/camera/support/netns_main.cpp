// main() of test programs that need loopback addresses of their own: each run enters a
// private network namespace with 127.0.0.2 and 127.0.0.3 on lo, so tests neither need the
// host's addresses nor leave any behind, and runs in parallel never share GVCP port 3956.
#include <gtest/gtest.h>

#include <cstdio>
#include <exception>

#include "tactile/camera/private_network.hpp"

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  if (!GTEST_FLAG_GET(list_tests)) {
    try {
      // Before any thread exists: a user namespace needs a single-threaded process.
      tactile::camera::enter_private_network({"127.0.0.2", "127.0.0.3"});
    } catch (const std::exception& e) {
      std::fprintf(stderr,
                   "FAIL: these tests need a private network namespace with 127.0.0.2 and "
                   "127.0.0.3 on lo, and could not make one: %s\n",
                   e.what());
      return 1;
    }
  }
  return RUN_ALL_TESTS();
}
