// The headers nearly every test file parses first: GoogleTest, Eigen and the standard library.
// tests/CMakeLists.txt precompiles them once per tree and every test reuses the copy (3-4 s of
// each test file's compile on two cores, about a tenth of the trees' builds). Only headers the
// tests take as they are, with no configuration macro set before them: a test file still
// includes what it uses, and builds the same without this file (RSD_TEST_PCH=OFF).
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>
