// A command's output is never one of its inputs, nor inside an input folder.
#include "core/base/output_path.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

#include "core/base/error.h"

namespace lumistage {
namespace {

namespace fs = std::filesystem;

std::string errorOf(const fs::path& output, std::initializer_list<CommandInput> inputs) {
  try {
    refuseOutputOverInputs("--out", output, inputs);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(OutputPath, AnOutputOverOrInsideAnInputIsRefused) {
  const fs::path dir =
      fs::temp_directory_path() / ("lumistage_output_path_" + std::to_string(::getpid()));
  fs::create_directories(dir / "session" / "cam01");
  std::ofstream(dir / "points.txt") << "x\n";
  const fs::path session = dir / "session", points = dir / "points.txt";
  // The same file, however it is spelt.
  std::string e = errorOf(dir / "." / "points.txt", {{"--points", points}});
  EXPECT_NE(e.find("it is --points " + points.string() + ", which the command reads"),
            std::string::npos)
      << e;
  // Inside a session folder (the file there or not yet), or the folder itself.
  e = errorOf(session / "session.yaml", {{"--points", points}, {"--session", session}});
  EXPECT_NE(e.find("inside --session " + session.string()), std::string::npos) << e;
  EXPECT_NE(errorOf(session / "cam01" / "new.png", {{"--session", dir / "session" / ""}}),
            "no error");
  EXPECT_NE(errorOf(session, {{"--session", session}}), "no error");
  // Beside them, or with the inputs left out: fine.
  EXPECT_EQ(errorOf(dir / "session2" / "x.json", {{"--session", session}}), "no error");
  EXPECT_EQ(errorOf(dir / "rig.yaml", {{"--points", points}, {"--session", ""}}), "no error");
  EXPECT_EQ(errorOf("", {{"--session", session}}), "no error");
  // A file input is no folder: an output "inside" it is not refused here (its open fails).
  EXPECT_EQ(errorOf(points / "x", {{"--points", points}}), "no error");
  // A folder to write into: checked before the work.
  EXPECT_NO_THROW(requireOutputFolder("--json", dir / "r.json"));
  EXPECT_NO_THROW(requireOutputFolder("--json", ""));
  try {
    requireOutputFolder("--json", dir / "nodir" / "r.json");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no folder " + (dir / "nodir").string()),
              std::string::npos)
        << e.what();
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace lumistage
