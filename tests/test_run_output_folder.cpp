// cge::run::OutputFolder: all-or-nothing output folders (cge/run/output_folder.hpp). Each case
// builds a folder by hand, runs the folder through a successful or a failed run, and compares every
// file and folder with what was there before.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cge/run/output_folder.hpp"
#include "temp_dir.hpp"

namespace {

namespace fs = std::filesystem;
using cge::run::OutputFolder;

const char* kTool = "test_tool";
const std::vector<std::string> kNames = {"a.txt", "b.txt"};

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
}

/// Every entry below `folder`: relative path -> file contents ("<folder>" for folders).
std::map<std::string, std::string> snapshot(const fs::path& folder) {
  std::map<std::string, std::string> entries;
  for (const auto& e : fs::recursive_directory_iterator(folder)) {
    const std::string name = e.path().lexically_relative(folder).string();
    if (e.is_directory()) {
      entries[name] = "<folder>";
    } else {
      std::ifstream f(e.path(), std::ios::binary);
      std::ostringstream text;
      text << f.rdbuf();
      entries[name] = text.str();
    }
  }
  return entries;
}

/// The pid of a process that has exited and been reaped (no process has it right after).
pid_t dead_pid() {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  int status = 0;
  ::waitpid(child, &status, 0);
  return child;
}

}  // namespace

TEST_CASE("OutputFolder: a committed run creates the folder and moves its files in", "[run][output_folder]") {
  const cge_test::TempDir tmp("cge_output_folder");
  const fs::path out = tmp.path() / "new" / "out";
  {
    OutputFolder folder(out, false, kTool, kNames);
    folder.write("a.txt", [](std::ostream& f) { f << "alpha\n"; });
    REQUIRE_FALSE(fs::exists(out / "a.txt"));  // staged, not yet in place
    CHECK(folder.staging_folder().parent_path() == out);
    folder.commit();
  }
  CHECK(snapshot(out) == std::map<std::string, std::string>{{"a.txt", "alpha\n"}});
}

TEST_CASE("OutputFolder: a failed run leaves an existing folder as it was", "[run][output_folder]") {
  const cge_test::TempDir tmp("cge_output_folder");
  const fs::path out = tmp.path() / "out";
  fs::create_directory(out);
  write_text(out / "a.txt", "the previous run's a\n");
  write_text(out / "notes.txt", "the user's own file\n");
  const auto before = snapshot(out);
  {
    OutputFolder folder(out, true, kTool, kNames);
    folder.write("a.txt", [](std::ostream& f) { f << "new a\n"; });
    folder.write("b.txt", [](std::ostream& f) { f << "new b\n"; });
    // destroyed without commit(): the run failed
  }
  CHECK(snapshot(out) == before);
}

TEST_CASE("OutputFolder: a failed run removes the folders it created", "[run][output_folder]") {
  const cge_test::TempDir tmp("cge_output_folder");
  {
    OutputFolder folder(tmp.path() / "x" / "y", false, kTool, kNames);
    folder.write("a.txt", [](std::ostream& f) { f << "a\n"; });
  }
  CHECK(snapshot(tmp.path()).empty());
}

TEST_CASE("OutputFolder: --force replaces only the tool's files", "[run][output_folder]") {
  const cge_test::TempDir tmp("cge_output_folder");
  const fs::path out = tmp.path();
  write_text(out / "a.txt", "old a\n");
  write_text(out / "b.txt", "old b\n");
  write_text(out / "notes.txt", "mine\n");
  {
    OutputFolder folder(out, true, kTool, kNames);
    folder.write("a.txt", [](std::ostream& f) { f << "new a\n"; });
    folder.commit();
  }
  CHECK(snapshot(out) ==
        std::map<std::string, std::string>{{"a.txt", "new a\n"}, {"b.txt", "old b\n"}, {"notes.txt", "mine\n"}});
}

TEST_CASE("OutputFolder: refusals change nothing and name the problem", "[run][output_folder]") {
  const cge_test::TempDir tmp("cge_output_folder");
  const fs::path out = tmp.path() / "out";
  fs::create_directory(out);
  write_text(out / "notes.txt", "mine\n");
  const auto before = snapshot(tmp.path());
  SECTION("not empty, no force") {
    try {
      OutputFolder folder(out, false, kTool, kNames);
      FAIL("a non-empty folder was accepted without force");
    } catch (const std::invalid_argument& e) {
      CHECK(std::string(e.what()) ==
            "'" + out.string() + "' exists and is not empty (use --force to replace test_tool's files in it)");
    }
  }
  SECTION("a folder where a file goes") {
    fs::create_directory(out / "b.txt");
    const auto with_folder = snapshot(tmp.path());
    try {
      OutputFolder folder(out, true, kTool, kNames);
      FAIL("a folder at an output's name was accepted");
    } catch (const std::invalid_argument& e) {
      CHECK(std::string(e.what()) ==
            "'" + (out / "b.txt").string() + "' exists and is not a file: test_tool cannot replace it");
    }
    CHECK(snapshot(tmp.path()) == with_folder);
    return;
  }
  SECTION("a file where the folder goes") {
    CHECK_THROWS_AS(OutputFolder(out / "notes.txt", true, kTool, kNames), std::invalid_argument);
  }
  CHECK(snapshot(tmp.path()) == before);
}

TEST_CASE("OutputFolder: a dead process's staging folder is a leftover, a live one is not", "[run][output_folder]") {
  const cge_test::TempDir tmp("cge_output_folder");
  const fs::path out = tmp.path();
  const fs::path stale = out / (std::string(".") + kTool + ".partial." + std::to_string(dead_pid()));
  fs::create_directory(stale);
  write_text(stale / "a.txt", "a killed run's file\n");
  CHECK(cge::run::is_stale_staging(stale, kTool));
  CHECK_FALSE(cge::run::is_stale_staging(stale, "other_tool"));
  CHECK_FALSE(cge::run::is_stale_staging(out / (std::string(".") + kTool + ".partial.12x"), kTool));
  CHECK_FALSE(cge::run::is_stale_staging(out / (std::string(".") + kTool + ".partial." + std::to_string(::getpid())),
                                         kTool));
  {
    OutputFolder folder(out, false, kTool, kNames);  // no force needed: the folder holds only a leftover
    CHECK_FALSE(fs::exists(stale));
    folder.write("b.txt", [](std::ostream& f) { f << "b\n"; });
    folder.commit();
  }
  CHECK(snapshot(out) == std::map<std::string, std::string>{{"b.txt", "b\n"}});

  // The parent process is alive: its staging folder is someone's running work, not a leftover.
  const fs::path other = out / "other";
  const fs::path live = other / (std::string(".") + kTool + ".partial." + std::to_string(::getppid()));
  fs::create_directories(live);
  CHECK_FALSE(cge::run::is_stale_staging(live, kTool));
  CHECK_THROWS_AS(OutputFolder(other, false, kTool, kNames), std::invalid_argument);
  CHECK(fs::is_directory(live));
}
