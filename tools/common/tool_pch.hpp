// The headers nearly every tool's file parses first: CLI11, Eigen and the standard library.
// tools/CMakeLists.txt precompiles them once per tree and every tool target reuses the copy
// (CLI11 alone is about 4 s of parsing in each of the tools' translation units). Only headers
// the tools take as they are, with no configuration macro set before them: a file still includes
// what it uses, and builds the same without this one (RSD_TOOL_PCH=OFF).
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <Eigen/Dense>
