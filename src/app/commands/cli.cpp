#include "src/app/commands/cli.hpp"

#include <fmt/format.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <exception>
#include <new>
#include <stdexcept>

#include "garment/panel_tasks.hpp"
#include "sim/parallel.hpp"
#include "src/app/version.hpp"

namespace sd::app {
namespace {

void configure_logging(const GlobalOptions& global) {
  auto logger = spdlog::stderr_color_mt("sketchdrape");
  logger->set_pattern("%^%l%$: %v");
  spdlog::set_default_logger(logger);
  spdlog::set_level(global.quiet     ? spdlog::level::err
                    : global.verbose ? spdlog::level::debug
                                     : spdlog::level::info);
}

}  // namespace

CLI::Validator finite_range(double low, double high) {
  return CLI::Validator(
      [low, high](std::string& text) -> std::string {
        double value = 0;
        try {
          size_t used = 0;
          value = std::stod(text, &used);
          if (used != text.size()) return "'" + text + "' is not a number";
        } catch (const std::exception&) {
          return "'" + text + "' is not a number";
        }
        if (!std::isfinite(value)) return "'" + text + "' is not a finite number";
        if (value < low || value > high)
          return fmt::format("{} is outside {:g} .. {:g}", text, low, high);
        return {};
      },
      fmt::format("NUMBER in [{:g}, {:g}]", low, high));
}

int run_cli(int argc, char** argv) {
  CLI::App app{"sketchdrape: sketch-based garment design — quad meshing, cloth draping, previews"};
  app.set_version_flag("--version", std::string("sketchdrape ") + kVersion);
  app.require_subcommand(1);
  app.fallthrough();
  GlobalOptions global;
  app.add_flag("-q,--quiet", global.quiet, "Only print errors; no progress bars");
  app.add_flag("-v,--verbose", global.verbose, "Print debug logs (GL version, timings, ...)");
  app.add_option("--threads", global.threads,
                 "Threads for the simulator's parallel loops (contact queries) and for meshing "
                 "panels side by side; default: every core. Results are the same bits for any "
                 "count")
      ->check(CLI::Range(1, 256));
  app.parse_complete_callback([&] {
    configure_logging(global);
    sim::set_thread_count(global.threads);
    garment::set_panel_threads(global.threads);
  });

  add_info_command(app, global);
  add_fill_command(app, global);
  add_render_command(app, global);
  add_validate_command(app, global);
  add_mesh_command(app, global);
  add_pattern_command(app, global);
  add_run_command(app, global);
  add_batch_command(app, global);
  add_stress_command(app, global);
  add_bench_command(app, global);
  add_dent_command(app, global);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kExitBadInput;
  } catch (const std::invalid_argument& e) {
    spdlog::error("{}", e.what());
    return kExitBadInput;
  } catch (const std::bad_alloc&) {
    spdlog::error(
        "out of memory: the command needed more memory than the system could give it "
        "(run's --max-memory refuses such work before it starts)");
    return kExitFailure;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace sd::app
