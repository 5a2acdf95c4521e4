// Everything scatter-load is told on its command line, parsed once (main.cpp) and passed down.
#pragma once

#include <chrono>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace scatter::load {

struct LoadOptions {
  // The daemon.
  std::string host = "127.0.0.1", port = "8080", token;
  int pid = 0;             // when /metrics has no process_resident_memory_bytes: VmRSS of this pid
  double timeout_s = 120;  // connect, handshake, one request; and the longest silence of a session

  // What is rendered (hello of a live session, body of a REST render or bake).
  std::string scene = "sphere", pipeline = "surface", terms, format = "jpg";
  nlohmann::json settings = nlohmann::json::object();

  // Bounds: seconds (0: none), frames per live session (0: none), cycles per REST client (0: none).
  double duration_s = 10;
  long long frames = 0, cycles = 0;
  double rss_interval_s = 1;

  // live
  int sessions = 1;
  std::string path = "orbit";  // orbit, random-walk, burst
  double rate_hz = 30, orbit_deg_s = 30;
  int burst_poses = 10, burst_pause_ms = 1000;
  int light_every = 0;  // a lights message after every N poses (0: never)
  unsigned seed = 1;

  // rest
  int clients = 1;
  std::vector<std::string> ops = {"render"};  // render, bake
  int poll_ms = 200;
};

// A timer's duration from seconds given on the command line.
inline std::chrono::steady_clock::duration span(double seconds) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(seconds));
}

}  // namespace scatter::load
