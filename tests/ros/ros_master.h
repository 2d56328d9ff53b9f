// A real ROS master on the loopback for one test process: `roscore -p PORT` on a free port with
// ROS_HOME and the logs in a temporary directory, this process a ROS node of it, and child
// processes (the `upd ros` node) started in their own process groups. Everything started is
// stopped by its process group at the end (roscore's rosmaster and rosout children included).
#pragma once

#include "temp_dir.h"

#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <ros/ros.h>

#include <chrono>
#include <fcntl.h>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace upd::test {

/// A TCP port nobody listens on right now.
inline int freePort() {
  const int s = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  socklen_t len = sizeof a;
  if (::bind(s, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
      ::getsockname(s, reinterpret_cast<sockaddr*>(&a), &len) != 0) {
    ::close(s);
    throw std::runtime_error("no free port");
  }
  ::close(s);
  return ntohs(a.sin_port);
}

/// A child process in its own process group, stdout and stderr into log_path.
class Child {
 public:
  Child(const std::vector<std::string>& argv, const std::string& log_path) : log_(log_path) {
    pid_ = ::fork();
    if (pid_ == 0) {
      ::setpgid(0, 0);
      const int fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      std::vector<char*> args;
      for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      ::execvp(args[0], args.data());
      ::_exit(127);
    }
    ::setpgid(pid_, pid_);
  }
  ~Child() { stop(); }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  /// The exit status once it ended within timeout_s, -1 otherwise (still running).
  int waitExit(double timeout_s) {
    if (status_ >= 0) return status_;
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    for (;;) {
      int st = 0;
      if (::waitpid(pid_, &st, WNOHANG) == pid_) {
        status_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
        return status_;
      }
      if (std::chrono::steady_clock::now() >= until) return -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  /// SIGINT to the group, then SIGKILL if it lingers.
  void stop() {
    if (pid_ <= 0 || status_ >= 0) return;
    ::kill(-pid_, SIGINT);
    if (waitExit(5.0) < 0) {
      ::kill(-pid_, SIGKILL);
      waitExit(2.0);
    }
  }
  std::string log() const {
    std::ifstream in(log_);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }

 private:
  pid_t pid_ = -1;
  int status_ = -1;
  std::string log_;
};

/// roscore on a free loopback port; this process joins it as node `name`.
class RosMasterOnLoopback {
 public:
  explicit RosMasterOnLoopback(const std::string& name) : home_("ros_home") {
    const int port = freePort();
    const std::string uri = "http://127.0.0.1:" + std::to_string(port);
    ::setenv("ROS_MASTER_URI", uri.c_str(), 1);
    ::setenv("ROS_IP", "127.0.0.1", 1);
    ::setenv("ROS_HOME", home_.path().c_str(), 1);
    ::setenv("ROS_LOG_DIR", (home_.path() / "log").c_str(), 1);
    // The navigator's PTG cache of this process and its children: two tests building the
    // shared one at once could read each other's half-written files.
    ::setenv("XDG_CACHE_HOME", (home_.path() / "cache").c_str(), 1);
    core_ = std::make_unique<Child>(std::vector<std::string>{"roscore", "-p", std::to_string(port)},
                                    (home_.path() / "roscore.log").string());
    int argc = 0;
    ros::init(argc, nullptr, name, ros::init_options::NoSigintHandler);
    for (int i = 0; i < 200 && !ros::master::check(); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    if (!ros::master::check()) throw std::runtime_error("roscore did not start: " + core_->log());
    ros::start();
  }
  ~RosMasterOnLoopback() {
    ros::shutdown();
    core_.reset();  // SIGINT to roscore's group: rosmaster and rosout end with it
  }
  const std::filesystem::path& dir() const { return home_.path(); }

 private:
  TempDir home_;
  std::unique_ptr<Child> core_;
};

}  // namespace upd::test
