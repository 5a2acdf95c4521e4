// The daemon: listens on one port, serves the Api over HTTP; one render thread (RenderQueue)
// owns the GPU; Asio threads do the I/O; a small worker pool runs request handlers.
#pragma once

#include <boost/asio.hpp>
#include <memory>
#include <thread>
#include <vector>

#include "bake/cache.hpp"
#include "server/api.hpp"

namespace scatter::server {

struct ServerOptions {
  std::string bind = "127.0.0.1";
  unsigned short port = 8080;  // 0: any free port (see Server::port())
  size_t max_upload_mb = 64;
  int io_threads = 2;
  int workers = 4;
  ApiOptions api;
  gpu::GpuOptions gpu;
  std::shared_ptr<BakeCache> cache;  // bake products; null: a memory-only cache
};

class Server {
 public:
  // Binds and starts listening; throws std::runtime_error if the address cannot be bound.
  explicit Server(ServerOptions options);
  ~Server();
  unsigned short port() const { return port_; }
  // Serves until stop() (or SIGINT/SIGTERM when `handle_signals`).
  void run(bool handle_signals);
  void stop();

 private:
  void do_accept();

  ServerOptions options_;
  RenderQueue queue_;
  Metrics metrics_;
  Api api_;
  boost::asio::io_context io_;
  boost::asio::thread_pool workers_;
  boost::asio::ip::tcp::acceptor acceptor_;
  unsigned short port_ = 0;
};

}  // namespace scatter::server
