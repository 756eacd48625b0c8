#pragma once
// The options every network subcommand shares (--models, --dtype, --seed), the flag of those that remove
// a background (--raw-matte), and the summary line they print.
#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "pipeline/network_stage.h"

namespace u3d::cli {

struct NetworkArgs {
  NetworkOptions options;
  std::string dtype = "auto";
  // The options with --dtype resolved ("auto" leaves the device's default).
  NetworkOptions resolved() const;
};

// --models (required unless `models_required` is false: `batch` needs it only for photos) and --dtype, and
// --seed for the stages that draw noise.
void add_network_options(CLI::App& sub, NetworkArgs& args, bool seeded = true, bool models_required = true);

// --raw-matte: the commands that remove a photo's background (matte, multiview, refine, generate).
void add_raw_matte_flag(CLI::App& sub, bool& raw_matte);

// "time: load 1.2 s, multi-view 30.1 s, ..., total ...; bf16; peak memory 2100 MiB" and the files written.
void print_stage_summary(const NetworkStageSummary& summary);

}  // namespace u3d::cli
