#include "engine/scheduler.h"

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <set>
#include <thread>

#include "engine/key.h"

namespace pb {
namespace {

using Clock = std::chrono::steady_clock;

// The figures kept with a cache entry. `warnings` only when there are some,
// so entries of stages without warnings keep their earlier form.
nlohmann::json RecordOf(const JobResult& r) {
  nlohmann::json record = {{"wall_s", r.wall_s},         {"user_s", r.user_s},
                           {"sys_s", r.sys_s},           {"peak_rss_bytes", r.peak_rss_bytes},
                           {"read_bytes", r.read_bytes}, {"write_bytes", r.write_bytes},
                           {"counters", r.counters},     {"phases", r.phases}};
  if (!r.warnings.empty()) record["warnings"] = r.warnings;
  return record;
}

std::vector<std::string> WarningsOf(const nlohmann::json& record) {
  std::vector<std::string> out;
  if (record.is_object() && record.contains("warnings") && record["warnings"].is_array())
    for (const auto& w : record["warnings"])
      if (w.is_string()) out.push_back(w.get<std::string>());
  return out;
}

}  // namespace

const char* StateName(StageOutcome::State state) {
  switch (state) {
    case StageOutcome::State::kPending: return "pending";
    case StageOutcome::State::kRunning: return "running";
    case StageOutcome::State::kHit: return "hit";
    case StageOutcome::State::kRan: return "ran";
    case StageOutcome::State::kFailed: return "failed";
    case StageOutcome::State::kSkipped: return "skipped";
  }
  return "?";
}

void Scheduler::RunOne(StageOutcome& out, const std::map<std::string, StageOutcome>& done,
                       const RunOptions& options, double) {
  const StageNode& node = wf_.stages.at(out.id);
  std::map<std::string, std::string> digests;
  JobSpec job;
  job.stage_id = out.id;
  job.type = node.type;
  job.params = node.params;
  job.plugins = wf_.plugins;
  job.threads = options.threads_per_stage;
  job.peak_estimate_bytes = node.type->declared_peak_bytes;
  if (auto h = cache_.LoadHistory(wf_.name, out.id)) {
    job.peak_estimate_bytes = h->value("peak_rss_bytes", job.peak_estimate_bytes);
    job.wall_estimate_s = h->value("wall_s", 0.0);
  }
  for (const auto& [port, in] : node.inputs) {
    const auto& upstream = done.at(in.from_stage).outputs;
    if (!upstream.count(in.from_port)) {
      out.state = StageOutcome::State::kFailed;
      out.error = "upstream '" + in.from_stage + "' has no output '" + in.from_port +
                  "' in its cached result (its stage type changed without a version bump; "
                  "run `pointbake cache gc` or set a workflow salt)";
      return;
    }
    const Artifact& art = upstream.at(in.from_port);
    digests[port] = art.ComputeDigest().Hex();
    ArtifactView view;
    view.type = art.type;
    view.meta = art.meta;
    for (const auto& [name, file] : art.files) view.files[name] = cache_.ObjectPath(file.digest);
    job.inputs[port] = std::move(view);
  }
  Expected<nlohmann::json> comps = KeyComponents(node, wf_.salt, digests, cache_);
  if (!comps.ok()) {
    out.state = StageOutcome::State::kFailed;
    out.error = comps.status().message();
    return;
  }
  out.components = *comps;
  const Digest key = KeyOf(*comps);
  out.key = key.Hex();
  auto hit = [&](CacheEntry entry) {
    out.state = StageOutcome::State::kHit;
    out.outputs = std::move(entry.outputs);
    out.cached_record = entry.record;
    out.warnings = WarningsOf(entry.record);
  };
  out.forced = options.force.count(out.id) > 0 &&
               (!options.forced_keys || options.forced_keys->Claim(out.key));
  if (!out.forced)
    if (std::optional<CacheEntry> entry = cache_.Lookup(key)) return hit(std::move(*entry));

  // Another run may be computing the same key: wait for it, then reuse.
  bool would_block = false;
  Expected<FileLock> lock = cache_.LockKey(key, false, &would_block);
  if (lock.ok() && would_block) {
    if (observer_) observer_->OnStageWaiting(out.id, "the same result is being computed elsewhere; waiting to reuse it");
    lock = cache_.LockKey(key, true);
  }
  if (!lock.ok()) {
    out.state = StageOutcome::State::kFailed;
    out.error = lock.status().message();
    return;
  }
  if (!out.forced)
    if (std::optional<CacheEntry> entry = cache_.Lookup(key)) return hit(std::move(*entry));

  if (observer_) observer_->OnStageStart(out.id, node.type->id);
  Expected<std::string> staging = cache_.NewStagingDir(key);
  if (!staging.ok()) {
    out.state = StageOutcome::State::kFailed;
    out.error = staging.status().message();
    return;
  }
  job.staging_dir = *staging;
  if (!options.log_dir.empty()) job.log_path = JoinPath(options.log_dir, out.id + ".log");
  ProgressFn progress = [&](double f) {
    if (observer_) observer_->OnStageProgress(out.id, f);
  };
  out.result = executor_.Run(job, progress);
  out.warnings = out.result.warnings;
  if (!out.result.status.ok()) {
    out.state = StageOutcome::State::kFailed;
    out.error = out.result.status.message();
    (void)Env::Default()->RemoveAll(*staging);
    return;
  }
  Expected<CacheEntry> entry =
      cache_.Commit(key, *comps, out.result.outputs, RecordOf(out.result), *staging);
  if (!entry.ok()) {
    out.state = StageOutcome::State::kFailed;
    out.error = "storing results in the cache: " + entry.status().message();
    (void)Env::Default()->RemoveAll(*staging);
    return;
  }
  out.state = StageOutcome::State::kRan;
  out.outputs = std::move(entry->outputs);
  (void)cache_.SaveHistory(wf_.name, out.id,
                           {{"components", *comps},
                            {"key", out.key},
                            {"peak_rss_bytes", out.result.peak_rss_bytes},
                            {"wall_s", out.result.wall_s}});
}

std::vector<StageOutcome> Scheduler::Run(const RunOptions& options) {
  const auto t0 = Clock::now();
  auto now_s = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  std::mutex mu;
  std::condition_variable cv;
  std::map<std::string, StageOutcome> outcomes;
  for (const std::string& id : wf_.order) {
    StageOutcome o;
    o.id = id;
    o.type = wf_.stages.at(id).type->id;
    outcomes[id] = o;
  }
  // Peak memory each stage is expected to need: learned, else declared.
  std::map<std::string, uint64_t> mem_estimate;
  for (const std::string& id : wf_.order) {
    uint64_t est = wf_.stages.at(id).type->declared_peak_bytes;
    if (auto h = cache_.LoadHistory(wf_.name, id)) est = h->value("peak_rss_bytes", est);
    mem_estimate[id] = est;
  }
  const int jobs = std::max(1, options.jobs);
  int running = 0;
  uint64_t running_mem = 0;
  int finished = 0;
  bool stop = false;
  std::vector<bool> slot_busy(static_cast<size_t>(jobs), false);
  std::vector<std::thread> threads;
  std::map<std::string, StageOutcome> done_snapshot;  // finished outcomes, read by workers

  std::unique_lock<std::mutex> lock(mu);
  for (;;) {
    // Propagate failures to dependents.
    for (const std::string& id : wf_.order) {
      StageOutcome& o = outcomes[id];
      if (o.state != StageOutcome::State::kPending) continue;
      for (const std::string& dep : wf_.stages.at(id).deps) {
        const auto st = outcomes[dep].state;
        if (st == StageOutcome::State::kFailed || st == StageOutcome::State::kSkipped) {
          o.state = StageOutcome::State::kSkipped;
          o.error = "not run: upstream stage '" + dep + "' " +
                    (st == StageOutcome::State::kFailed ? "failed" : "did not run");
          ++finished;
          if (observer_) observer_->OnStageEnd(o, finished, static_cast<int>(wf_.order.size()));
          break;
        }
      }
    }
    // Launch what is ready.
    for (const std::string& id : wf_.order) {
      if (stop || running >= jobs) break;
      StageOutcome& o = outcomes[id];
      if (o.state != StageOutcome::State::kPending) continue;
      bool ready = true;
      for (const std::string& dep : wf_.stages.at(id).deps) {
        const auto st = outcomes[dep].state;
        if (st != StageOutcome::State::kHit && st != StageOutcome::State::kRan) ready = false;
      }
      if (!ready) continue;
      const uint64_t est = mem_estimate[id];
      if (options.mem_budget_bytes > 0 && running > 0 &&
          running_mem + est > options.mem_budget_bytes)
        continue;  // held back until memory frees up
      o.state = StageOutcome::State::kRunning;
      o.start_s = now_s();
      int slot = 0;
      while (slot_busy[static_cast<size_t>(slot)]) ++slot;
      slot_busy[static_cast<size_t>(slot)] = true;
      o.slot = slot;
      ++running;
      running_mem += est;
      for (const std::string& dep : wf_.stages.at(id).deps) done_snapshot[dep] = outcomes[dep];
      threads.emplace_back([&, id, est, snapshot = done_snapshot] {
        StageOutcome local;
        {
          std::lock_guard<std::mutex> g(mu);
          local = outcomes[id];
        }
        try {
          RunOne(local, snapshot, options, 0);
        } catch (const std::exception& e) {
          local.state = StageOutcome::State::kFailed;
          local.error = std::string("internal error: ") + e.what();
        }
        std::lock_guard<std::mutex> g(mu);
        local.end_s = now_s();
        outcomes[id] = local;
        slot_busy[static_cast<size_t>(local.slot)] = false;
        --running;
        running_mem -= est;
        ++finished;
        if (local.state == StageOutcome::State::kFailed && !options.keep_going) stop = true;
        if (observer_) observer_->OnStageEnd(local, finished, static_cast<int>(wf_.order.size()));
        cv.notify_all();
      });
    }
    if (running == 0) {
      bool any_ready = false;
      if (!stop)
        for (const std::string& id : wf_.order)
          if (outcomes[id].state == StageOutcome::State::kPending) any_ready = true;
      if (!any_ready) break;
      // Pending stages exist but none launched: only possible after a stop.
      if (stop) break;
      continue;
    }
    cv.wait(lock);
  }
  lock.unlock();
  for (auto& t : threads) t.join();
  std::vector<StageOutcome> result;
  for (const std::string& id : wf_.order) {
    StageOutcome& o = outcomes[id];
    if (o.state == StageOutcome::State::kPending) {
      o.state = StageOutcome::State::kSkipped;
      o.error = "not run: the run stopped after a failure (use --keep-going to run independent stages)";
      ++finished;
      if (observer_) observer_->OnStageEnd(o, finished, static_cast<int>(wf_.order.size()));
    }
    result.push_back(o);
  }
  return result;
}

}  // namespace pb
