#include "cli/cli.h"
#include "cli/executor_config.h"

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <set>
#include <thread>

#include "base/env.h"
#include "engine/cache.h"
#include "engine/executor.h"
#include "engine/key.h"
#include "engine/progress.h"
#include "engine/run_record.h"
#include "engine/run_workflow.h"
#include "engine/scheduler.h"
#include "engine/slurm_executor.h"
#include "engine/workflow.h"

namespace pb {
namespace {

struct RunFlags {
  std::string workflow;
  std::string scene;
  std::vector<std::string> sets;
  int jobs = 1;
  std::string mem;
  std::string cache_dir;
  std::string out_dir;
  bool dry_run = false;
  bool keep_going = false;
  bool quiet = false;
  bool in_process = false;
  int threads = 0;
  std::vector<std::string> force;  // --force STAGE
  std::vector<std::string> until;  // --until STAGE
  ExecutorFlags executor;  // run and campaign only
};

constexpr const char* kCacheHelp =
    "Cache folder (default $POINTBAKE_CACHE, else $XDG_CACHE_HOME/pointbake, else "
    "~/.cache/pointbake)";

void AddWorkflowOptions(CLI::App* cmd, RunFlags& f) {
  cmd->add_option("WORKFLOW", f.workflow, "Workflow YAML file")->required();
  cmd->add_option("--scene", f.scene, "Scene file (overrides the workflow's scene:)")
      ->type_name("FILE");
  cmd->add_option("--set", f.sets, "Override a parameter (repeatable)")
      ->type_name("STAGE.PARAM=VALUE")
      ->allow_extra_args(false);
}

// The options that choose what runs: shared by `run` and `explain`.
void AddSelectionOptions(CLI::App* cmd, RunFlags& f) {
  AddWorkflowOptions(cmd, f);
  cmd->add_option("--cache", f.cache_dir, kCacheHelp)->type_name("DIR");
  cmd->add_option("--force", f.force,
                  "Run STAGE even if it is cached; its result replaces the cache entry, and "
                  "its dependents re-run unless its outputs come out unchanged (repeatable)")
      ->type_name("STAGE")
      ->allow_extra_args(false);
  cmd->add_option("--until", f.until,
                  "Run only STAGE and the stages it needs, and copy its outputs (repeatable)")
      ->type_name("STAGE")
      ->allow_extra_args(false);
}

void AddRunOptions(CLI::App* cmd, RunFlags& f) {
  AddSelectionOptions(cmd, f);
  cmd->add_option("-j,--jobs", f.jobs, "Stages run in parallel")
      ->check(CLI::Range(1, 256))
      ->type_name("N");
  cmd->add_option("--mem", f.mem, "Memory budget for parallel stages, e.g. 16G")->type_name("SIZE");
  cmd->add_option("--out", f.out_dir, "Output folder (default out/<workflow name>)")
      ->type_name("DIR");
  cmd->add_option("--threads", f.threads, "Threads per stage (default: all cores)")->type_name("N");
}

std::string DefaultCacheDir() {
  if (const char* env = std::getenv("POINTBAKE_CACHE"); env && *env) return env;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::string(xdg) + "/pointbake";
  if (const char* home = std::getenv("HOME"); home && *home) return std::string(home) + "/.cache/pointbake";
  return ".pointbake-cache";
}

int Fail(const Status& st) {
  std::fprintf(stderr, "%s\n", st.message().c_str());
  return 2;
}

// Loads the workflow and applies --until; checks the ids of --force.
Expected<Workflow> Load(const RunFlags& f, Registry& registry) {
  LoadOptions opts;
  opts.scene_file = f.scene;
  opts.sets = f.sets;
  PB_ASSIGN_OR_RETURN(Workflow wf, LoadWorkflow(f.workflow, opts, registry));
  if (!f.until.empty()) PB_RETURN_IF_ERROR(KeepUpstreamOf(wf, f.until));
  PB_RETURN_IF_ERROR(CheckStageIds(wf, f.force, "--force"));
  return wf;
}

struct PlanCounts {
  int hit = 0, run = 0, maybe = 0, earlier = 0;
  void Add(const std::vector<PlanLine>& plan) {
    for (const PlanLine& line : plan) {
      switch (line.state) {
        case PlanLine::State::kHit:
          ++hit;
          break;
        case PlanLine::State::kMiss:
          ++run;
          break;
        case PlanLine::State::kDependsOnUpstream:
          ++maybe;
          break;
        case PlanLine::State::kEarlierRun:
          ++earlier;
          break;
      }
    }
  }
  std::string Text() const {
    std::string text = std::to_string(hit) + " cached, " + std::to_string(run) + " to run, " +
                       std::to_string(maybe) + " to run unless upstream outputs come out unchanged";
    if (earlier > 0) text += ", " + std::to_string(earlier) + " computed by an earlier run";
    return text;
  }
};

// One line per stage: hit / run / run? / reuse, id, type, key; then the
// reasons (for hits too when `reasons_for_hits`). `skip_hits` leaves hits out.
void PrintPlanLines(const std::vector<PlanLine>& plan, bool reasons_for_hits, bool skip_hits,
                    const char* indent) {
  for (const PlanLine& line : plan) {
    const bool hit = line.state == PlanLine::State::kHit;
    if (hit && skip_hits) continue;
    const char* what = hit                                          ? "hit"
                       : line.state == PlanLine::State::kMiss       ? "run"
                       : line.state == PlanLine::State::kEarlierRun ? "reuse"
                                                                    : "run?";
    std::printf("%s%-5s %-20s %-22s %s\n", indent, what, line.stage.c_str(), line.type.c_str(),
                line.key.empty() ? "(key known once inputs are)" : line.key.substr(0, 16).c_str());
    if (reasons_for_hits || !hit)
      for (const std::string& r : line.reasons) std::printf("%s        - %s\n", indent, r.c_str());
  }
}

int PrintPlan(const Workflow& wf, Cache& cache, const RunFlags& f, bool explain) {
  PlanOptions options;
  options.force.insert(f.force.begin(), f.force.end());
  Expected<std::vector<PlanLine>> plan = PlanWorkflow(wf, cache, options);
  if (!plan.ok()) return Fail(plan.status());
  PrintPlanLines(*plan, explain, false, "");
  PlanCounts counts;
  counts.Add(*plan);
  std::printf("%s\n", counts.Text().c_str());
  return 0;
}

int CmdRun(const RunFlags& f, Registry& registry, bool explain_only) {
  // Paths travel to stages inside JSON job files, which hold UTF-8 only.
  for (const auto& [what, path] : {std::pair{"workflow", ResolvePath(".", f.workflow)},
                                   std::pair{"--cache", ResolvePath(".", f.cache_dir)},
                                   std::pair{"--out", ResolvePath(".", f.out_dir)}})
    if (!IsValidUtf8(path))
      return Fail(Status::Invalid(std::string(what) + " path is not valid UTF-8; rename the folder"));
  Expected<Workflow> wf = Load(f, registry);
  if (!wf.ok()) return Fail(wf.status());
  uint64_t mem = 0;
  if (!f.mem.empty()) {
    Expected<uint64_t> parsed = ParseByteSize(f.mem);
    if (!parsed.ok()) return Fail(parsed.status().WithContext("--mem"));
    mem = *parsed;
  }
  Expected<std::unique_ptr<Cache>> cache = Cache::Open(f.cache_dir.empty() ? DefaultCacheDir() : f.cache_dir);
  if (!cache.ok()) return Fail(cache.status());
  Expected<FileLock> shared = (*cache)->LockShared();
  if (!shared.ok()) return Fail(shared.status());
  if (explain_only || f.dry_run) return PrintPlan(*wf, **cache, f, explain_only);

  const std::string out_dir = f.out_dir.empty() ? "out/" + wf->name : f.out_dir;
  WorkflowRunOptions opts;
  opts.jobs = f.jobs;
  opts.mem_budget_bytes = mem;
  opts.keep_going = f.keep_going;
  opts.threads_per_stage = f.threads;
  opts.quiet = f.quiet;
  opts.in_process = f.in_process;
  opts.sets = f.sets;
  opts.force.insert(f.force.begin(), f.force.end());
  opts.until = f.until;
  Expected<std::unique_ptr<Executor>> executor = MakeExecutor(f.executor);
  if (!executor.ok()) return Fail(executor.status());
  opts.executor = executor->get();
  const WorkflowRunSummary r = RunWorkflowInto(*wf, **cache, opts, out_dir);
  if (SlurmExecutor::Interrupted()) std::fprintf(stderr, "interrupted: submitted Slurm jobs were cancelled\n");
  if (!r.outputs.ok()) {
    std::fprintf(stderr, "writing outputs: %s\n", r.outputs.message().c_str());
    return 2;
  }
  if (!f.quiet)
    for (const auto& w : r.written) std::printf("output %s\n", w.c_str());
  std::printf("%s: %s in %s; record in %s/run.json\n", wf->name.c_str(), SummaryCounts(r).c_str(),
              FormatSeconds(r.total_s).c_str(), out_dir.c_str());
  return r.failed > 0 || r.skipped > 0 ? 1 : 0;
}

struct CampaignFlags {
  std::string file;
  RunFlags run;
  bool explain = false;  // `campaign explain FILE`
};

// The demo campaign: configs/campaigns/demo.yaml under the working directory,
// else in the source tree this binary was built from.
std::string DemoCampaignFile() {
  const std::string local = "configs/campaigns/demo.yaml";
  if (Env::Default()->Exists(local)) return local;
  return std::string(PB_SOURCE_DIR) + "/" + local;
}

// `campaign --dry-run` and `campaign explain`: each run's plan, in order. A
// key an earlier run computes counts as "reuse" in the later ones (the runs
// share the cache), so the totals say what the campaign would really run.
int PrintCampaignPlan(const Campaign& campaign, Cache& cache, Registry& registry, bool explain,
                      const std::vector<std::string>& force) {
  std::printf("campaign %s: %zu runs; %s\n", campaign.name.c_str(), campaign.runs.size(),
              explain ? "per stage: cached or not, and why" : "dry run, nothing runs");
  std::set<std::string> planned;
  PlanCounts total;
  for (size_t i = 0; i < campaign.runs.size(); ++i) {
    const CampaignRun& run = campaign.runs[i];
    LoadOptions opts;
    opts.scene_file = run.scene_file;
    opts.sets = run.sets;
    Expected<Workflow> wf = LoadWorkflow(run.workflow_file, opts, registry);
    if (!wf.ok()) return Fail(wf.status());
    PlanOptions plan_options;
    plan_options.planned_keys = &planned;
    plan_options.force.insert(force.begin(), force.end());
    Expected<std::vector<PlanLine>> plan = PlanWorkflow(*wf, cache, plan_options);
    if (!plan.ok()) return Fail(plan.status());
    PlanCounts counts;
    counts.Add(*plan);
    total.Add(*plan);
    std::printf("[%zu/%zu] %s: %s\n", i + 1, campaign.runs.size(), run.name.c_str(),
                counts.Text().c_str());
    PrintPlanLines(*plan, explain, !explain, "  ");
  }
  std::printf("campaign %s: %s\n", campaign.name.c_str(), total.Text().c_str());
  return 0;
}

int CmdCampaign(const CampaignFlags& f, Registry& registry, const CampaignReportWriter& report) {
  for (const auto& [what, path] : {std::pair{"campaign", ResolvePath(".", f.file)},
                                   std::pair{"--cache", ResolvePath(".", f.run.cache_dir)},
                                   std::pair{"--out", ResolvePath(".", f.run.out_dir)}})
    if (!IsValidUtf8(path))
      return Fail(Status::Invalid(std::string(what) + " path is not valid UTF-8; rename the folder"));
  if (!Env::Default()->Exists(f.file)) return Fail(Status::NotFound("campaign file not found: " + f.file));
  Expected<Campaign> campaign = LoadCampaign(f.file, registry);
  if (!campaign.ok()) return Fail(campaign.status());
  uint64_t mem = 0;
  if (!f.run.mem.empty()) {
    Expected<uint64_t> parsed = ParseByteSize(f.run.mem);
    if (!parsed.ok()) return Fail(parsed.status().WithContext("--mem"));
    mem = *parsed;
  }
  Expected<std::unique_ptr<Cache>> cache =
      Cache::Open(f.run.cache_dir.empty() ? DefaultCacheDir() : f.run.cache_dir);
  if (!cache.ok()) return Fail(cache.status());
  Expected<FileLock> shared = (*cache)->LockShared();
  if (!shared.ok()) return Fail(shared.status());
  if (Status st = CheckCampaignStageIds(*campaign, f.run.force, "--force"); !st.ok())
    return Fail(st);
  if (f.run.dry_run || f.explain)
    return PrintCampaignPlan(*campaign, **cache, registry, f.explain, f.run.force);
  CampaignOptions options;
  options.out_dir = f.run.out_dir;
  options.run.jobs = f.run.jobs;
  options.run.mem_budget_bytes = mem;
  options.run.keep_going = f.run.keep_going;
  options.run.threads_per_stage = f.run.threads;
  options.run.quiet = f.run.quiet;
  options.run.force.insert(f.run.force.begin(), f.run.force.end());
  Expected<std::unique_ptr<Executor>> executor = MakeExecutor(f.run.executor);
  if (!executor.ok()) return Fail(executor.status());
  options.run.executor = executor->get();
  // On a cluster every run goes out at once; the scheduler there queues them.
  if (*executor) options.parallel_runs = static_cast<int>(campaign->runs.size());
  std::printf("campaign %s: %zu runs into %s\n", campaign->name.c_str(), campaign->runs.size(),
              (options.out_dir.empty() ? "out/" + campaign->name : options.out_dir).c_str());
  const CampaignResult r = RunCampaign(*campaign, **cache, options, registry, report);
  if (SlurmExecutor::Interrupted()) std::fprintf(stderr, "interrupted: submitted Slurm jobs were cancelled\n");
  if (!r.report.ok()) {
    std::fprintf(stderr, "writing the report: %s\n", r.report.message().c_str());
    return 2;
  }
  std::printf("campaign %s: %d runs, %d failed; results in %s/campaign.json\n", campaign->name.c_str(),
              r.runs, r.failed_runs, r.out_dir.c_str());
  if (!r.report_dir.empty())
    std::printf("report: %s/report.html (tables: %s/report.md, %s/results.csv)\n",
                r.report_dir.c_str(), r.report_dir.c_str(), r.report_dir.c_str());
  return r.failed_runs > 0 ? 1 : 0;
}

void AddCampaignOptions(CLI::App* cmd, CampaignFlags& f) {
  cmd->add_option("-j,--jobs", f.run.jobs, "Stages run in parallel within a run")
      ->check(CLI::Range(1, 256))
      ->type_name("N");
  cmd->add_option("--mem", f.run.mem, "Memory budget for parallel stages, e.g. 16G")
      ->type_name("SIZE");
  cmd->add_option("--cache", f.run.cache_dir, kCacheHelp)->type_name("DIR");
  cmd->add_flag("-n,--dry-run", f.run.dry_run,
                "Show what each run would run and what is cached; run nothing");
  cmd->add_option("--out", f.run.out_dir, "Output folder (default out/<campaign name>)")
      ->type_name("DIR");
  cmd->add_option("--threads", f.run.threads, "Threads per stage (default: all cores)")
      ->type_name("N");
  cmd->add_flag("--keep-going", f.run.keep_going, "After a failure, still run independent stages");
  cmd->add_flag("-q,--quiet", f.run.quiet, "Print failures and summaries only");
  cmd->add_option("--force", f.run.force,
                  "Run STAGE in every run that has it even if it is cached, once per cache key "
                  "(runs that share it reuse the new entry); its dependents re-run unless its "
                  "outputs come out unchanged (repeatable)")
      ->type_name("STAGE")
      ->allow_extra_args(false);
  AddExecutorOptions(cmd, f.run.executor);
}

// A scene names data, units, spacing, viewpoints or parameters; anything else
// is checked as a workflow (so a workflow that lost its `stages:` is reported
// as such, not accepted as a scene).
bool LooksLikeWorkflow(const nlohmann::json& value) {
  if (!value.is_object() || value.contains("stages")) return true;
  for (const char* key : {"points", "units", "spacing_m", "viewpoints", "params", "preset"})
    if (value.contains(key)) return false;
  return true;
}

int CmdValidate(const std::vector<std::string>& files, const std::string& as, Registry& registry) {
  int bad = 0;
  for (const std::string& file : files) {
    Expected<YamlDocument> doc = ParseYamlFile(file);
    Status st;
    if (!doc.ok()) {
      st = doc.status();
    } else if (as == "campaign" || (as.empty() && doc->value.is_object() &&
                                    doc->value.contains("scenes") && doc->value.contains("workflows"))) {
      Expected<Campaign> campaign = LoadCampaign(file, registry);
      if (!campaign.ok()) st = campaign.status();
    } else if (as == "workflow" || (as.empty() && LooksLikeWorkflow(doc->value))) {
      Expected<Workflow> wf = LoadWorkflow(file, {}, registry);
      if (!wf.ok()) st = wf.status();
    } else {
      Expected<nlohmann::json> scene = LoadScene(file);
      if (!scene.ok()) st = scene.status();
    }
    if (st.ok()) {
      std::printf("%s: ok\n", file.c_str());
    } else {
      ++bad;
      std::fprintf(stderr, "%s\n", st.message().c_str());
    }
  }
  return bad ? 2 : 0;
}

int CmdStages(const std::string& id, Registry& registry) {
  if (id.empty()) {
    for (const StageType* t : registry.All()) std::printf("%-22s %s\n", t->id.c_str(), t->summary.c_str());
    return 0;
  }
  const StageType* t = registry.Find(id);
  if (!t) {
    std::vector<std::string> ids;
    for (const StageType* type : registry.All()) ids.push_back(type->id);
    std::fprintf(stderr, "unknown stage type '%s'%s (see `pointbake stages`)\n", id.c_str(),
                 DidYouMean(id, ids).c_str());
    return 2;
  }
  std::printf("%s", DescribeStage(*t).c_str());
  return 0;
}

}  // namespace

constexpr const char* kHelpFooter = R"(
Examples:
  pointbake demo                                   the paper's comparison on synthetic rooms
  pointbake run configs/workflows/quickstart.yaml  run one workflow (outputs in out/quickstart/)
  pointbake run WF.yaml --set normals.k=24 -n      what a change would re-run, and why
  pointbake run WF.yaml --until normals            only 'normals' and what it needs
  pointbake run WF.yaml --force bake               re-run 'bake' although it is cached
  pointbake campaign configs/campaigns/demo.yaml -n   what a campaign would run
  pointbake stages points.normals                  a stage type's ports and parameters
  pointbake COMMAND --help, pointbake help COMMAND   the options of one command

Environment:
  POINTBAKE_CACHE   the cache folder (else $XDG_CACHE_HOME/pointbake, else ~/.cache/pointbake)
  XDG_CACHE_HOME    see POINTBAKE_CACHE

Exit status: 0 done; 1 a stage (or a campaign run) failed or did not run because of
one; 2 bad input or usage (nothing ran).

Documentation: README.md (a tour), docs/engine.md (cache, --force, --until,
warnings), docs/campaigns.md, docs/report.md.)";

int CliMain(int argc, char** argv, Registry& registry, const std::vector<CliCommand>& extra,
            const CampaignReportWriter& report) {
  for (const std::string& e : registry.TakeErrors())
    std::fprintf(stderr, "internal error registering built-in stages: %s\n", e.c_str());
  // The hidden child-process entry point, kept out of CLI11 for speed.
  if (argc == 3 && std::string(argv[1]) == "__stage") return RunStageSubcommand(argv[2], registry);
  // The same inside a Slurm job: runs __stage as a child and measures it.
  if (argc == 3 && std::string(argv[1]) == "__job") return RunSlurmJobSubcommand(argv[2], registry);
  // `pointbake help [COMMAND...]` is `pointbake [COMMAND...] --help`.
  std::vector<char*> help_args;
  if (argc >= 2 && std::string(argv[1]) == "help") {
    static char help_flag[] = "--help";
    help_args.push_back(argv[0]);
    for (int i = 2; i < argc; ++i) help_args.push_back(argv[i]);
    help_args.push_back(help_flag);
    argc = static_cast<int>(help_args.size());
    argv = help_args.data();
  }
  // Extra commands parse their own arguments.
  if (argc >= 2)
    for (const CliCommand& command : extra)
      if (command.name == argv[1]) return command.run(std::vector<std::string>(argv + 2, argv + argc));

  // The name is set, so usage lines say `pointbake`, not the path it was run by.
  CLI::App app{"pointbake: point clouds to VR-ready textured meshes, as cached workflows",
               "pointbake"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "pointbake 0.1.0");
  RunFlags run_flags, explain_flags, graph_flags;
  CLI::App* run = app.add_subcommand("run", "Run a workflow");
  AddRunOptions(run, run_flags);
  run->add_flag("-n,--dry-run", run_flags.dry_run, "Show what would run and why, run nothing");
  run->add_flag("--keep-going", run_flags.keep_going, "After a failure, still run independent stages");
  run->add_flag("-q,--quiet", run_flags.quiet, "Print failures and the summary only");
  run->add_flag("--in-process", run_flags.in_process,
                "Run stages inside this process (debugging; no per-stage memory figures)");
  AddExecutorOptions(run, run_flags.executor);
  CampaignFlags campaign_flags, demo_flags;
  campaign_flags.run.jobs = demo_flags.run.jobs = 2;
  CLI::App* campaign = app.add_subcommand("campaign", "Run a campaign (scenes x workflows) and write its report");
  campaign->add_option("FILE", campaign_flags.file, "Campaign YAML file");
  AddCampaignOptions(campaign, campaign_flags);
  CampaignFlags campaign_explain_flags;
  CLI::App* campaign_explain = campaign->add_subcommand(
      "explain", "Per run and stage: cached or not, and why (runs nothing)");
  campaign_explain->add_option("FILE", campaign_explain_flags.file, "Campaign YAML file")
      ->required();
  campaign_explain->add_option("--cache", campaign_explain_flags.run.cache_dir, kCacheHelp)
      ->type_name("DIR");
  CLI::App* demo = app.add_subcommand(
      "demo", "Run the demo campaign (synthetic scenes, the four workflows); report in out/demo/report/");
  AddCampaignOptions(demo, demo_flags);
  CLI::App* validate = app.add_subcommand("validate", "Check workflow, scene and campaign files, run nothing");
  std::vector<std::string> validate_files;
  validate->add_option("FILE", validate_files, "Workflow or scene files")->required();
  std::string validate_as;
  validate->add_option("--as", validate_as, "Check as this kind (default: decided by content)")
      ->check(CLI::IsMember({"workflow", "scene", "campaign"}));
  CLI::App* explain = app.add_subcommand("explain", "Per stage: cached or not, and what changed");
  AddSelectionOptions(explain, explain_flags);
  CLI::App* graph = app.add_subcommand("graph", "Print the workflow's DAG as Graphviz DOT");
  AddWorkflowOptions(graph, graph_flags);
  CLI::App* stages = app.add_subcommand("stages", "List stage types, or document one");
  std::string stage_id;
  stages->add_option("TYPE", stage_id, "Stage type id, e.g. points.downsample");
  CLI::App* cache = app.add_subcommand("cache", "Inspect and maintain the cache");
  cache->require_subcommand(1);
  std::string cache_dir;
  cache->add_option("--cache", cache_dir, kCacheHelp)->type_name("DIR");
  CLI::App* cache_ls = cache->add_subcommand("ls", "List entries, most recently used first");
  CLI::App* cache_gc = cache->add_subcommand("gc", "Evict least recently used entries down to a size");
  CLI::App* cache_verify = cache->add_subcommand("verify", "Re-hash every object, check every entry");
  // `--cache DIR` is accepted before or after the sub-command.
  for (CLI::App* sub : {cache_ls, cache_gc, cache_verify})
    sub->add_option("--cache", cache_dir, kCacheHelp)->type_name("DIR");
  std::string max_size;
  cache_gc->add_option("--max-size", max_size, "Size to keep, e.g. 20G")->required();
  bool repair = false;
  cache_verify->add_flag("--repair", repair, "Remove what is corrupt");
  // Listed in --help only; dispatched above.
  for (const CliCommand& command : extra) app.add_subcommand(command.name, command.summary);
  // After the sub-commands: they would inherit it.
  app.footer(kHelpFooter);

  // CLI11 takes an unknown first word for a stray argument: `pointbake nosuch
  // --help` would print the main help and succeed. Say what is wrong instead.
  if (argc >= 2 && argv[1][0] != '-') {
    std::vector<std::string> names;
    for (const CLI::App* sub : app.get_subcommands({})) names.push_back(sub->get_name());
    if (std::find(names.begin(), names.end(), argv[1]) == names.end()) {
      std::string list;
      for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
      std::fprintf(stderr,
                   "pointbake: unknown command '%s'%s\ncommands: %s (see `pointbake --help`)\n",
                   argv[1], DidYouMean(argv[1], names).c_str(), list.c_str());
      return 2;
    }
  }
  if (argc == 1) {
    std::fprintf(stderr, "%s", app.help().c_str());
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  if (*run) return CmdRun(run_flags, registry, false);
  if (*campaign_explain) {
    campaign_explain_flags.explain = true;
    return CmdCampaign(campaign_explain_flags, registry, report);
  }
  if (*campaign) {
    if (campaign_flags.file.empty())
      return Fail(Status::Invalid(
          "campaign: a campaign FILE is required (see `pointbake campaign --help`)"));
    return CmdCampaign(campaign_flags, registry, report);
  }
  if (*demo) {
    demo_flags.file = DemoCampaignFile();
    return CmdCampaign(demo_flags, registry, report);
  }
  if (*explain) return CmdRun(explain_flags, registry, true);
  if (*validate) return CmdValidate(validate_files, validate_as, registry);
  if (*stages) return CmdStages(stage_id, registry);
  if (*graph) {
    Expected<Workflow> wf = Load(graph_flags, registry);
    if (!wf.ok()) return Fail(wf.status());
    std::printf("%s", WorkflowToDot(*wf).c_str());
    return 0;
  }
  if (*cache) {
    Expected<std::unique_ptr<Cache>> c = Cache::Open(cache_dir.empty() ? DefaultCacheDir() : cache_dir);
    if (!c.ok()) return Fail(c.status());
    if (*cache_ls) {
      Expected<FileLock> lock = (*c)->LockShared();
      Expected<std::vector<Cache::EntryInfo>> entries = (*c)->ListEntries();
      if (!entries.ok()) return Fail(entries.status());
      uint64_t total = 0;
      for (const auto& e : *entries) {
        const std::time_t t = static_cast<std::time_t>(e.last_used_ns / 1000000000);
        char when[32];
        std::strftime(when, sizeof when, "%Y-%m-%d %H:%M", std::localtime(&t));
        std::printf("%s  %-22s %10s  %s\n", e.key.Hex().c_str(), e.stage_type.c_str(),
                    FormatBytes(e.bytes).c_str(), when);
        total += e.bytes;
      }
      std::printf("%zu entries, %s (shared objects counted per entry) in %s\n", entries->size(),
                  FormatBytes(total).c_str(), (*c)->dir().c_str());
      return 0;
    }
    if (*cache_gc) {
      Expected<uint64_t> bytes = ParseByteSize(max_size);
      if (!bytes.ok()) return Fail(bytes.status().WithContext("--max-size"));
      Expected<FileLock> lock = (*c)->LockExclusive();
      if (!lock.ok()) return Fail(lock.status());
      Expected<GcReport> r = (*c)->Gc(*bytes);
      if (!r.ok()) return Fail(r.status());
      std::printf("gc: %s -> %s; removed %d entries, %d objects, %d temporary leftovers\n",
                  FormatBytes(r->bytes_before).c_str(), FormatBytes(r->bytes_after).c_str(),
                  r->entries_removed, r->objects_removed, r->temp_removed);
      return 0;
    }
    if (*cache_verify) {
      Expected<FileLock> lock = repair ? (*c)->LockExclusive() : (*c)->LockShared();
      if (!lock.ok()) return Fail(lock.status());
      Expected<VerifyReport> r = (*c)->Verify(repair);
      if (!r.ok()) return Fail(r.status());
      for (const auto& p : r->problems) std::printf("%s\n", p.c_str());
      std::printf("verify: %d entries, %d objects checked, %zu problems%s\n", r->entries_checked,
                  r->objects_checked, r->problems.size(),
                  repair ? (", " + std::to_string(r->removed) + " removed").c_str() : "");
      return r->problems.empty() || repair ? 0 : 1;
    }
  }
  return 2;
}

}  // namespace pb
