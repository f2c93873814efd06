// A study: one specimen scanned at several loading stages, optionally its DEM
// twin (one run, or a sweep of variants), and the comparison between them;
// described by one TOML file (docs/studies.md lists every key, the example is
// examples/study.toml). This module reads and checks the file and turns it
// into a plan of steps with content keys; apps/cmd_run.cpp runs the steps by
// calling the same commands a user would (segment, measure, psd, track, dem,
// compare), and workflow/Snakefile hands the same steps to Snakemake.
//
// Strict: an unknown key, a missing scan, stages of different shapes or
// strains that do not increase are InputErrors naming the file and the key,
// raised before any step starts.
#pragma once
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>
#include <toml++/toml.h>

namespace tg::study {

struct Stage {
  std::string name;   // [[stage]] name, default "stage<i>"
  std::string scan;   // absolute path (relative ones are taken from the study file's folder)
  double strain = 0;  // axial strain, fraction
};

struct DemVariant {
  std::string name;        // "" for the single run of a study without variants
  toml::table overrides;   // dotted DEM config key -> value ([[dem.variant]] set = {...})
};

struct Study {
  std::filesystem::path file;  // the study file, absolute
  std::string source;          // the study file as the user named it (for messages)
  std::string name;            // [study] name, default the file's stem
  double grain_diameter_um = 1360.0;
  double voxel_um = 0;         // 0: the scans' own
  std::vector<Stage> stages;
  // Options of the commands, as in the file: keys are the commands' long
  // option names (apps/config_args.hpp turns them into arguments).
  toml::table segment, measure, psd, track, compare;
  bool track_enabled = true;   // [track] enabled (default: on with two or more stages)
  bool track_scans = false;    // [track] scans: the stages' scans go to track (rotations)
  std::filesystem::path dem_config;  // absolute; empty = no DEM and no comparison
  std::string dem_text;              // its text, read once
  std::vector<DemVariant> variants;  // one entry (name "") without [[dem.variant]]
};

// Reads and checks a study file. Throws InputError("FILE: KEY problem").
Study read_study(const std::filesystem::path& file);

// The DEM config of a variant: the study's DEM config with the variant's
// overrides set (re-serialised by toml++), or the file's text unchanged.
std::string dem_config_text(const Study& s, const DemVariant& v);

// ---------------------------------------------------------------- plan

enum class StepKind { analyse, track, dem, compare, summary };

struct Step {
  std::string id;                    // "analyse-<stage>", "track", "dem[-<v>]", "compare[-<v>]", "summary"
  StepKind kind;
  int stage = -1;                    // analyse: index into Study::stages
  int variant = -1;                  // dem, compare: index into Study::variants
  std::vector<std::string> needs;    // ids of the steps whose outputs it reads
  std::filesystem::path output;      // the folder it writes (replaced as a whole)
  std::vector<std::filesystem::path> inputs;  // files outside DIR whose content it reads
  int threads = 2;                   // resources for a scheduler (workflow/Snakefile)
  int64_t mem_mb = 1000;
  int runtime_min = 10;
};

struct Plan {
  std::filesystem::path dir;   // the study's output folder, absolute
  std::vector<Step> steps;     // in an order that respects `needs`
  const Step& step(const std::string& id) const;  // InputError for an unknown id
  std::filesystem::path record(const Step& s) const { return dir / ".run" / (s.id + ".json"); }
};

// `voxels` of one scan (0 if unknown) sizes the memory and time requests.
Plan make_plan(const Study& s, const std::filesystem::path& dir, int64_t voxels_per_scan);

// The plan as JSON for schedulers (`tomograin run --plan`).
std::string plan_json(const Study& s, const Plan& p);

}  // namespace tg::study
