#pragma once

// What the command-line tests (cli_*_test.cpp) share: the programs under test, the reference rig,
// a scratch path and a free port of their own, and a synthesized session to run on.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/app/shell_command.h"

namespace lumistage::testing {

inline const std::string kCli = LUMISTAGE_CLI;
inline const std::string kNode = LUMISTAGE_NODE;
inline const std::string kReference =
    std::string(LUMISTAGE_TEST_RESOURCE_DIR) + "/rigs/reference.yaml";

// A TCP port on 127.0.0.1 that nothing listens on (the system's pick, released at once).
inline int freePort() {
  const int s = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t size = sizeof(address);
  if (s < 0 || ::bind(s, reinterpret_cast<sockaddr*>(&address), size) != 0 ||
      ::getsockname(s, reinterpret_cast<sockaddr*>(&address), &size) != 0) {
    ADD_FAILURE() << "no free port";
  }
  ::close(s);
  return ntohs(address.sin_port);
}

inline std::filesystem::path tempPath(const std::string& name) {
  return std::filesystem::temp_directory_path() /
         ("lumistage_cli_" + std::to_string(::getpid()) + "_" + name);
}

// folder/session: `lumistage synth <synth_options>` of a studio whose rig is `lumistage rig ring
// <rig_options>` (folder/rig.yaml) and whose other sections are `studio` (YAML).
inline ::testing::AssertionResult synthRingSession(const std::filesystem::path& folder,
                                                   const std::string& rig_options,
                                                   const std::string& studio,
                                                   const std::string& synth_options) {
  std::filesystem::create_directories(folder);
  Result r = run(kCli + " rig ring " + rig_options + " --out " + (folder / "rig.yaml").string());
  if (r.exit_code != 0) return ::testing::AssertionFailure() << r.output;
  std::ofstream(folder / "studio.yaml") << "format: lumistage-studio\nversion: 1\nrig: rig.yaml\n"
                                        << studio;
  r = run(kCli + " synth --config " + (folder / "studio.yaml").string() + " " + synth_options +
          " --out " + (folder / "session").string());
  if (r.exit_code != 0) return ::testing::AssertionFailure() << r.output;
  return ::testing::AssertionSuccess();
}

}  // namespace lumistage::testing
