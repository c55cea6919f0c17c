// The `hsr` command line: the table of subcommands, `hsr help`, and main(), which turns every
// failure into one line on stderr and an exit status (docs/conventions.md "Command line": 0
// success, 2 bad usage or input, 1 otherwise). Each subcommand lives in apps/NAME_cmd.cpp
// (commands.hpp); docs/cli.md documents them.
#include <hsr/hsr.hpp>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <iostream>
#include <map>
#include <memory>

#include "commands.hpp"

namespace hsr::cli {
namespace {

Runner setupHelp(CLI::App& cmd);

// The subcommands, in the order `hsr help` lists them.
struct Subcommand {
  const char* name;
  const char* summary;
  Runner (*setup)(CLI::App&);
};
const Subcommand kSubcommands[] = {
    {"render", "Render a scene to colour, face-id and depth files, with statistics", setupRender},
    {"bench", "Time repeated renders of a scene: median and minimum", setupBench},
    {"batch", "Render the views of a manifest, or one shard of them, into a folder with an index; resumable",
     setupBatch},
    {"algorithms", "List the visibility algorithms: parameters, sources and guarantees", setupAlgorithms},
    {"scenes", "List the built-in scenes and their parameters", setupScenes},
    {"info", "Describe a scene: counts, meshes, bounds, problems, camera", setupInfo},
    {"compare", "The documents' comparisons: every algorithm on the study's scenes, a table, results.json and an "
                "HTML report", setupCompare},
    {"precision", "Depth precision per format: separable depth differences and the spread of stored values",
     setupPrecision},
    {"help", "Explain hsr or one of its commands", setupHelp},
};

Runner setupHelp(CLI::App& cmd) {
  auto topic = std::make_shared<std::string>();
  cmd.add_option("command", *topic, "Command to explain")->type_name("COMMAND");
  const CLI::App* root = cmd.get_parent();
  return [root, topic] {
    // App::help() of the root would describe the subcommand being run (this one): format the
    // root page directly.
    if (topic->empty()) {
      std::cout << root->get_formatter()->make_help(root, root->get_name(), CLI::AppFormatMode::Normal);
      return 0;
    }
    if (*topic == "algorithms") {  // the listing itself is the help
      printAlgorithms();
      return 0;
    }
    std::string known;
    for (const Subcommand& s : kSubcommands) {
      if (*topic == s.name) {
        std::cout << root->get_subcommand(s.name)->help(root->get_name());
        return 0;
      }
      known += (known.empty() ? "" : ", ") + std::string(s.name);
    }
    throw InputError("help: unknown command '" + *topic + "' (commands: " + known + ")");
  };
}

int runCli(int argc, char** argv) {
  CLI::App app("hsr " HSR_VERSION " - hidden-surface removal: an exact z-buffer and a lab of classic visibility algorithms",
               "hsr");
  app.set_version_flag("--version", "hsr " HSR_VERSION);
  app.require_subcommand(1);
  app.footer(
      "Run 'hsr help COMMAND' or 'hsr COMMAND --help' for a command's flags.\n"
      "Exit status: 0 success, 2 bad usage or bad input (one line on stderr), 1 any other failure.");
  std::map<const CLI::App*, Runner> runners;
  std::string maxMemory;
  std::vector<CLI::Option*> maxMemoryFlags;
  for (const Subcommand& s : kSubcommands) {
    CLI::App* cmd = app.add_subcommand(s.name, s.summary);
    runners[cmd] = s.setup(*cmd);
    maxMemoryFlags.push_back(cmd->add_option("--max-memory", maxMemory,
                    "Refuse up front a request that would need more memory than this (e.g. 512M, 4G; default: the "
                    "machine's available memory)")
        ->type_name("SIZE"));
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    const std::vector<CLI::App*> chosen = app.get_subcommands();
    std::string topic = chosen.empty() ? "hsr help" : "hsr help " + chosen.front()->get_name();
    throw InputError(std::string(e.what()) + " (see '" + topic + "')");
  }
  if (std::any_of(maxMemoryFlags.begin(), maxMemoryFlags.end(), [](CLI::Option* o) { return o->count() > 0; }))
    hsr::setMemoryLimit(hsr::parseMemorySize(maxMemory, "--max-memory"));
  return runners.at(app.get_subcommands().front())();  // require_subcommand(1): exactly one
}

// One line on stderr, whatever the message holds.
int fail(int status, std::string message) {
  std::replace(message.begin(), message.end(), '\n', ' ');
  std::cout.flush();
  std::cerr << "hsr: " << message << '\n';
  return status;
}

}  // namespace
}  // namespace hsr::cli

int main(int argc, char** argv) {
  try {
    return hsr::cli::runCli(argc, argv);
  } catch (const hsr::InputError& e) {
    return hsr::cli::fail(2, hsr::cli::cliMessage(e));
  } catch (const std::bad_alloc&) {
    return hsr::cli::fail(1, "error: out of memory");
  } catch (const std::exception& e) {
    return hsr::cli::fail(1, std::string("error: ") + e.what());
  } catch (...) {
    return hsr::cli::fail(1, "error: unknown exception");
  }
}