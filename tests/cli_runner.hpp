// Running the built `hsr` binary (HSR_CLI_PATH) in a test's scratch directory, as scripts do:
// its exit status, standard output and error. Used by the command-line tests.
#pragma once
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <ostream>
#include <string>

#include "temp_dir.hpp"

namespace hsr::test {

inline std::string readText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// What one run of the command gave.
struct CliResult {
  int status = -1;
  std::string out, err;
  // Usage errors are exactly one line "hsr: ...".
  bool oneErrorLine() const {
    return err.rfind("hsr: ", 0) == 0 && std::count(err.begin(), err.end(), '\n') == 1 && err.back() == '\n';
  }
};

inline std::ostream& operator<<(std::ostream& os, const CliResult& r) {
  return os << "status " << r.status << "\nstdout: " << r.out << "\nstderr: " << r.err;
}

/// A scratch directory and the command run in it.
class CliTest : public TempDirTest {
 protected:
  // Runs `hsr ARGS` in the scratch directory (ARGS is shell text: quote as needed).
  CliResult hsr(const std::string& args) const {
    std::string command = "cd '" + dir_.string() + "' && '" HSR_CLI_PATH "' " + args + " >stdout.txt 2>stderr.txt";
    int raw = std::system(command.c_str());
    CliResult result;
    result.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    result.out = readText(dir_ / "stdout.txt");
    result.err = readText(dir_ / "stderr.txt");
    std::filesystem::remove(dir_ / "stdout.txt");
    std::filesystem::remove(dir_ / "stderr.txt");
    return result;
  }
  std::filesystem::path file(const std::string& name) const { return dir_ / name; }
  void writeFile(const std::string& name, const std::string& text) const { std::ofstream(dir_ / name) << text; }
};

}  // namespace hsr::test
