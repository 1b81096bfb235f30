#pragma once
// The sketchdrape command line: subcommands, global flags and exit codes (docs/cli.md).

#include <CLI/CLI.hpp>
#include <string>

#include "garment/body.hpp"

namespace sd::app {

enum ExitCode : int {
  kExitOk = 0,        // the command did what was asked
  kExitFailure = 1,   // it could not (a solver diverged, a file could not be written, ...)
  kExitBadInput = 2,  // the user's input is wrong: usage, a bad sketch file, an unreadable body
};

// Flags every subcommand understands.
struct GlobalOptions {
  bool quiet = false;    // only errors on stderr, no progress bars
  bool verbose = false;  // debug logs (GL version, timings, solver details)
  int threads = 0;       // the simulator's parallel loops (sim/parallel.hpp); 0 = every core
};

// A command-line number check: finite (no nan, inf, 1e999) and within [low, high]. CLI11's own
// range checks let "nan" through (every comparison with NaN is false).
CLI::Validator finite_range(double low, double high, const std::string& unit = "");

// An output path that is not empty: `-o ''` wrote into the working directory (trial 36).
CLI::Validator non_empty_path();

// How to read a body file (docs/bodies.md, "Normalisation"), as a sketch's "body" object says
// it: `info` and `render` take the same options (--up, --facing, --height, --scale), so a body
// that needs one can be both described and drawn with its landmarks (trial 43, P12).
struct BodyFileOptions {
  std::string up;      // the file's up axis; inferred when empty
  std::string facing;  // the way the figure faces in the file; by the up axis's convention
  double height = 0;   // m; 0: not given
  double scale = 0;    // metres per file unit; 0: not given
  garment::BodyOptions body_options() const;
};
void add_body_file_options(CLI::App& cmd, BodyFileOptions& options);

// Parses argv, runs the chosen subcommand and maps exceptions to exit codes:
// std::invalid_argument (bad input) → 2, any other std::exception → 1.
int run_cli(int argc, char** argv);

// Each subcommand lives in its own <name>_command.cpp and registers itself here.
void add_info_command(CLI::App& app, const GlobalOptions& global);
void add_fill_command(CLI::App& app, const GlobalOptions& global);
void add_render_command(CLI::App& app, const GlobalOptions& global);
void add_validate_command(CLI::App& app, const GlobalOptions& global);
void add_mesh_command(CLI::App& app, const GlobalOptions& global);
void add_pattern_command(CLI::App& app, const GlobalOptions& global);
void add_run_command(CLI::App& app, const GlobalOptions& global);
void add_batch_command(CLI::App& app, const GlobalOptions& global);
void add_stress_command(CLI::App& app, const GlobalOptions& global);
void add_bench_command(CLI::App& app, const GlobalOptions& global);
void add_dent_command(CLI::App& app, const GlobalOptions& global);

}  // namespace sd::app
