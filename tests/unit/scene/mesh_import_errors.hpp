// What a mesh import says about a malformed file, for the mesh tests (mesh_test.cpp,
// mesh_checks_test.cpp): the load runs on a thread of its own, so a load that hangs fails the test.
#pragma once

#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "scene/mesh.hpp"

namespace scatter::test_mesh {

// Runs `load` on a thread of its own and gives it `seconds`: a load that blocks (on a FIFO) or
// loops fails the test instead of hanging the test binary (the thread is left behind).
template <class Load>
std::optional<std::string> error_within(Load load, double seconds, bool* timed_out) {
  auto done = std::make_shared<std::promise<std::optional<std::string>>>();
  auto result = done->get_future();
  std::thread([done, load] {
    try {
      load();
      done->set_value(std::nullopt);
    } catch (const std::runtime_error& e) {
      done->set_value(std::string(e.what()));
    }
  }).detach();
  *timed_out = result.wait_for(std::chrono::duration<double>(seconds)) != std::future_status::ready;
  return *timed_out ? std::optional<std::string>("timed out") : result.get();
}

// The error load_mesh_bytes gives for `bytes` as `format`, within 10 s; FAILs without one.
inline std::string import_error(const std::string& bytes, const std::string& format) {
  bool timed_out = false;
  auto error =
      error_within([bytes, format] { load_mesh_bytes(bytes, format, "upload"); }, 10, &timed_out);
  EXPECT_FALSE(timed_out) << format << " import still running after 10 s";
  EXPECT_TRUE(error.has_value()) << format << " import accepted a malformed file";
  return error.value_or("");
}

#define EXPECT_CONTAINS(text, part) EXPECT_NE((text).find(part), std::string::npos) << (text)

}  // namespace scatter::test_mesh
