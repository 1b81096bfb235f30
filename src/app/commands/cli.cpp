#include "src/app/commands/cli.hpp"

#include <fmt/format.h>
#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <memory>
#include <new>
#include <stdexcept>
#include <string_view>
#include <utility>

#include "garment/panel_tasks.hpp"
#include "garment/sketch_error.hpp"
#include "sim/edit_distance.hpp"
#include "sim/parallel.hpp"
#include "src/app/version.hpp"

namespace sd::app {
namespace {

// A log line's message as garment::printable writes it (a flag for spdlog's pattern): every
// error, warning and info line quotes the user's text (ids, fabric names, paths) without a
// control or bidi character reaching the terminal, whichever stage wrote it (trial 39, P7).
class PrintableMessage final : public spdlog::custom_flag_formatter {
 public:
  void format(const spdlog::details::log_msg& message, const std::tm& /*time*/,
              spdlog::memory_buf_t& out) override {
    const std::string text =
        garment::printable(std::string_view(message.payload.data(), message.payload.size()), true);
    out.append(text.data(), text.data() + text.size());
  }
  std::unique_ptr<custom_flag_formatter> clone() const override {
    return std::make_unique<PrintableMessage>();
  }
};

void configure_logging(const GlobalOptions& global) {
  if (spdlog::get("sketchdrape")) return;  // a second time: for an error after a failed parse
  auto logger = spdlog::stderr_color_mt("sketchdrape");
  auto formatter = std::make_unique<spdlog::pattern_formatter>();
  formatter->add_flag<PrintableMessage>('*').set_pattern("%^%l%$: %*");
  logger->set_formatter(std::move(formatter));
  spdlog::set_default_logger(logger);
  spdlog::set_level(global.quiet     ? spdlog::level::err
                    : global.verbose ? spdlog::level::debug
                                     : spdlog::level::info);
}

// The subcommands in the order --help lists them: "info, validate, mesh, ...".
std::string command_list(const CLI::App& app) {
  std::string list;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
    list += (list.empty() ? "" : ", ") + sub->get_name();
  return list;
}

// No command ran: none was given (CLI11's "A subcommand is required"), or the first word is not
// one (trial 35: `sketchdrape drape ...` was told the same), then with the likely one.
std::string missing_command_sentence(const CLI::App& app, int argc, char** argv) {
  std::string word;
  for (int i = 1; i < argc && word.empty(); ++i) {
    const std::string arg = argv[i];
    if (arg == "--threads") {
      ++i;  // its value
    } else if (!arg.starts_with("-")) {
      word = arg;
    }
  }
  if (word.empty())
    return fmt::format(
        "a command is required: sketchdrape COMMAND ..., one of {} "
        "(`sketchdrape --help` says what each does)",
        command_list(app));
  // Words a designer may reach for first.
  static const std::pair<const char*, const char*> kSynonyms[] = {
      {"drape", "run"},      {"simulate", "run"}, {"sim", "run"},         {"check", "validate"},
      {"lint", "validate"},  {"meshing", "mesh"}, {"flatten", "pattern"}, {"patterns", "pattern"},
      {"preview", "render"}, {"show", "render"},  {"body", "info"}};
  std::string best;
  for (const auto& [synonym, command] : kSynonyms)
    if (word == synonym) best = command;
  std::size_t closest = 3;  // close spellings only ("valdiate", "rnu")
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
    if (const std::size_t d = sim::edit_distance(word, sub->get_name());
        best.empty() && d < closest)
      best = sub->get_name(), closest = d;
  return fmt::format(
      "unknown command '{}'{}; the commands are {} (`sketchdrape --help` says what "
      "each does)",
      word, best.empty() ? "" : fmt::format(" (did you mean '{}'?)", best), command_list(app));
}

// The subcommand named on the command line, or null.
const CLI::App* command_in(const CLI::App& app, int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
      if (sub->get_name() == argv[i]) return sub;
  return nullptr;
}

// Any other command-line mistake (an extra file, a number out of range): CLI11's sentence in
// the program's "error: ..." form with where to read what the command takes (trial 36: its
// raw text came without the prefix, the only error that did).
std::string parse_error_sentence(const CLI::App& app, int argc, char** argv,
                                 const CLI::ParseError& e) {
  const CLI::App* command = command_in(app, argc, argv);
  std::string text = e.what();
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  // A global option's mistake (--threads 0 before the command) is explained by the program's
  // own --help, not the command's (trial 39, P15).
  for (const CLI::Option* option : app.get_options())
    for (const std::string& name : option->get_lnames())
      if (text.starts_with("--" + name + ":"))
        return fmt::format("{}; `sketchdrape --help` says what it takes", text);
  return command == nullptr ? fmt::format("{}; `sketchdrape --help` lists the commands", text)
                            : fmt::format("{}; `sketchdrape {} --help` says what it takes", text,
                                          command->get_name());
}

// An option the command does not have (trial 35: `run ... --duration 5` said "The following
// arguments were not expected: 5 --duration"): named, with where that setting lives when it is
// the sketch file's, else empty (CLI11's own message then).
std::string unknown_option_sentence(const CLI::App& app, int argc, char** argv) {
  const CLI::App* command = command_in(app, argc, argv);
  if (command == nullptr) return "";
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (!arg.starts_with("-") || arg == "-" || arg == "--") continue;
    const std::string name = arg.substr(0, arg.find('='));
    if (command->get_option_no_throw(name) != nullptr || app.get_option_no_throw(name) != nullptr)
      continue;
    // Settings of the sketch file that a user may look for on the command line.
    static const std::pair<const char*, const char*> kFileSettings[] = {
        {"duration", "\"simulate\": {\"duration\": SECONDS}"},
        {"time-step", "\"simulate\": {\"time_step\": SECONDS}"},
        {"dt", "\"simulate\": {\"time_step\": SECONDS}"},
        {"solver", "\"simulate\": {\"solver\": ...}"},
        {"adaptive", "\"simulate\": {\"adaptive\": true}"},
        {"rest", "\"simulate\": {\"rest\": \"flat\"}"},
        {"fabric", "\"fabric\": NAME"},
        {"edge-length", "\"edge_length\": METRES"},
        {"body", "\"body\": FILE"},
        {"images", "\"output\": {\"images\": [...]}"}};
    std::string bare = name.substr(name.find_first_not_of('-'));
    std::replace(bare.begin(), bare.end(), '_', '-');
    std::string where;
    for (const auto& [option, setting] : kFileSettings)
      if (bare == option)
        where = fmt::format(": that is a setting of the sketch file, {}", setting);
    return fmt::format("'{}' has no option {}{}; `sketchdrape {} --help` lists its options",
                       command->get_name(), name, where, command->get_name());
  }
  return "";
}

}  // namespace

CLI::Validator finite_range(double low, double high, const std::string& unit) {
  return CLI::Validator(
      [low, high, unit](std::string& text) -> std::string {
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
          return fmt::format("{} is outside {:g} .. {:g}{}", text, low, high,
                             unit.empty() ? "" : " " + unit);
        return {};
      },
      fmt::format("NUMBER in [{:g}, {:g}]", low, high));
}

CLI::Validator non_empty_path() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        return text.find_first_not_of(" \t") == std::string::npos
                   ? "an empty name is no place to write: give a folder (e.g. -o out)"
                   : std::string();
      },
      "PATH");
}

garment::BodyOptions BodyFileOptions::body_options() const {
  garment::BodyOptions out;
  if (!up.empty()) out.up = garment::AxisDirection::parse(up);
  if (!facing.empty()) out.facing = garment::AxisDirection::parse(facing);
  if (height > 0) out.height = height;
  if (scale > 0) out.scale = scale;
  return out;
}

void add_body_file_options(CLI::App& cmd, BodyFileOptions& options) {
  cmd.add_option("--up", options.up, "The file's up axis (x, y, z, -x, ...); inferred if omitted");
  cmd.add_option("--facing", options.facing,
                 "The way the figure faces in the file (x, -x, z, ...), across the up axis; by "
                 "the up axis's convention if omitted (Z up: -y, else +z)");
  cmd.add_option("--height", options.height, "Scale the body to this height in metres")
      ->check(finite_range(0.1, 5.0));
  cmd.add_option("--scale", options.scale, "Metres per file unit")->check(finite_range(1e-9, 1e9));
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

  // In the order of a design's work (look at the body, check, mesh, cut, drape, many at once),
  // then the tools: --help and the "no command" message list them so.
  add_info_command(app, global);
  add_validate_command(app, global);
  add_mesh_command(app, global);
  add_pattern_command(app, global);
  add_run_command(app, global);
  add_batch_command(app, global);
  add_render_command(app, global);
  add_fill_command(app, global);
  add_dent_command(app, global);
  add_bench_command(app, global);
  add_stress_command(app, global);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::RequiredError& e) {
    configure_logging(global);  // the parse stopped before it: "error: ..." as everywhere
    spdlog::error("{}", app.get_subcommands().empty() ? missing_command_sentence(app, argc, argv)
                                                      : parse_error_sentence(app, argc, argv, e));
    return kExitBadInput;
  } catch (const CLI::ExtrasError& e) {
    const std::string unknown = unknown_option_sentence(app, argc, argv);
    configure_logging(global);
    spdlog::error("{}", unknown.empty() ? parse_error_sentence(app, argc, argv, e) : unknown);
    return kExitBadInput;
  } catch (const CLI::ParseError& e) {
    configure_logging(global);
    spdlog::error("{}", parse_error_sentence(app, argc, argv, e));
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
