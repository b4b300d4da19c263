// SPDX-License-Identifier: MIT
#include "batch_run.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <filesystem>
#include <map>
#include <mutex>
#include <new>
#include <thread>
#include <utility>

#include "batch_progress.hpp"
#include "cli_args.hpp"
#include "commands.hpp"
#include "json_writer.hpp"
#include "pair_command.hpp"
#include "pose_math.hpp"
#include "report.hpp"
#include "transform_file.hpp"

namespace kissm_cli {
using namespace kissm_pose; // src/common/pose_math.hpp
namespace {

// The features of every distinct cloud (path and format) the pending pairs name: computed once, on first use,
// by whichever job needs them first (the others wait), and destroyed when the last pair naming them is done.
// A cloud that cannot be read or described keeps its message, so that every pair naming it gets the same
// line whichever job met it first.
class FeatureCache {
public:
    using Key = std::pair<std::string, int32_t>; // normalised path, format

    void add_reference(const Key &key) { ++entries_[key].references; }

    // The cloud's features, computed with `matcher` when no job has yet; nullptr with *error on failure.
    const kissm_features *acquire(const Key &key, kissm_matcher *matcher, std::string *error) {
        std::unique_lock<std::mutex> lock(mutex_);
        Entry &e = entries_.at(key);
        changed_.wait(lock, [&e] { return e.state != State::Loading; });
        if (e.state == State::Idle) {
            e.state = State::Loading;
            lock.unlock();
            std::string message;
            kissm_features *features = describe(key, matcher, &message);
            lock.lock();
            e.features = features;
            e.error = message;
            e.state = features ? State::Ready : State::Failed;
            changed_.notify_all();
        }
        *error = e.error;
        return e.features;
    }

    // One reference of a finished pair; the features go with the last.
    void release(const Key &key) {
        kissm_features *done = nullptr;
        {
            std::lock_guard<std::mutex> lock(mutex_);
            Entry &e = entries_.at(key);
            if (--e.references == 0 && e.state != State::Loading) {
                done = e.features;
                e.features = nullptr;
            }
        }
        kissm_features_destroy(done);
    }

    ~FeatureCache() {
        for (auto &entry : entries_) kissm_features_destroy(entry.second.features);
    }

private:
    enum class State { Idle, Loading, Ready, Failed };
    struct Entry {
        size_t references = 0;
        State state = State::Idle;
        kissm_features *features = nullptr;
        std::string error;
    };

    static kissm_features *describe(const Key &key, kissm_matcher *matcher, std::string *error) {
        kissm_cloud *raw = nullptr;
        int32_t status = kissm_read_points(key.first.c_str(), key.second, &raw);
        if (status != KISSM_OK) {
            *error = "cannot read it: " + library_error(status, key.first);
            return nullptr;
        }
        const CloudPtr cloud(raw);
        kissm_points points{};
        status = kissm_cloud_points(cloud.get(), &points);
        kissm_features *features = nullptr;
        if (status == KISSM_OK) status = kissm_features_compute(matcher, &points, &features);
        if (status != KISSM_OK) {
            *error = "cannot describe it: " + library_error(status);
            return nullptr;
        }
        return features;
    }

    std::mutex mutex_;
    std::condition_variable changed_;
    std::map<Key, Entry> entries_;
};

FeatureCache::Key cloud_key(const std::string &path, int32_t format) {
    return {std::filesystem::path(path).lexically_normal().string(), format};
}

// A row's clouds: its own files and formats when it has them (`kissm align`'s scans), else its paths resolved
// against the pairs file, with the row's format column or else the run's formats.
FeatureCache::Key source_key(const BatchRun &run, const PairRow &row) {
    if (!row.source_file.empty()) return cloud_key(row.source_file, row.source_file_format);
    return cloud_key(resolve_pair_path(run.pairs_file, row.source), row.format >= 0 ? row.format : run.source_format);
}
FeatureCache::Key target_key(const BatchRun &run, const PairRow &row) {
    if (!row.target_file.empty()) return cloud_key(row.target_file, row.target_file_format);
    return cloud_key(resolve_pair_path(run.pairs_file, row.target), row.format >= 0 ? row.format : run.target_format);
}

// Appends the lines, one write and flush each (a killed run loses no finished pair and leaves at most one
// partial line), counts them and keeps the progress line.
class ResultSink {
public:
    ResultSink(const BatchRun &run) : run_(run), progress_(run.pending.size(), run.progress, run.progress_label) {}

    // False once a write failed (the jobs then stop taking pairs).
    bool ok() const { return !failed_.load(); }

    void add(const std::string &line, bool error, bool valid) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (failed_.load()) return;
        if (std::fwrite(line.data(), 1, line.size(), run_.out) != line.size() || std::fflush(run_.out) != 0) {
            failed_.store(true);
            return;
        }
        size_t &count = error ? counts_.errors : (valid ? counts_.valid : counts_.invalid);
        ++count;
        progress_.pair_done();
    }

    BatchCounts finish() {
        progress_.finish();
        if (failed_.load()) throw UsageError("cannot write the results to '" + one_line(run_.out_name) + "'");
        return counts_;
    }

private:
    const BatchRun &run_;
    std::mutex mutex_;
    std::atomic<bool> failed_{false};
    BatchCounts counts_;
    BatchProgress progress_;
};

// One pair: its line, and whether it is an error or valid.
struct PairOutcome {
    std::string line;
    bool error = false;
    bool valid = false;
};

PairOutcome register_pair(const BatchRun &run, const PairRow &row, FeatureCache &cache, kissm_matcher *matcher) {
    PairOutcome o;
    const auto failed = [&](const std::string &message) {
        o.error = true;
        o.line = batch_line_error(row, run.has_gt_column, message);
        return o;
    };
    double gt[16];
    std::string error;
    if (!row.gt.empty() && !read_transform_file(resolve_pair_path(run.pairs_file, row.gt), gt, &error)) {
        return failed("gt: " + error);
    }
    // The source first, then the target: the message names the first that fails, whichever job runs the pair.
    const kissm_features *source = cache.acquire(source_key(run, row), matcher, &error);
    if (!source) return failed("source '" + one_line(row.source) + "': " + error);
    const kissm_features *target = cache.acquire(target_key(run, row), matcher, &error);
    if (!target) return failed("target '" + one_line(row.target) + "': " + error);
    kissm_result result{};
    int32_t status = kissm_result_init(&result, sizeof result);
    if (status == KISSM_OK) status = kissm_register_features(matcher, source, target, &result);
    if (status != KISSM_OK) return failed("cannot register: " + library_error(status));
    o.valid = result.valid != 0;
    o.line = batch_line_ok(row, run.has_gt_column, result, run.config.refine_mode, row.gt.empty() ? nullptr : gt);
    return o;
}

void add_common_fields(JsonWriter &json, const PairRow &row, bool has_gt_column) {
    json.begin_object();
    json.field("pair", row.index);
    json.field("source", row.source);
    json.field("target", row.target);
    if (has_gt_column) {
        json.key("gt");
        if (row.gt.empty()) {
            json.null();
        } else {
            json.value(row.gt);
        }
    }
}

} // namespace

std::string batch_line_ok(const PairRow &row, bool has_gt_column, const kissm_result &result, int32_t refine_mode,
                          const double *gt) {
    JsonWriter json(true);
    add_common_fields(json, row, has_gt_column);
    json.field("status", "ok");
    add_result_json(json, result, refine_mode, nullptr, false);
    if (gt) {
        // The demo's measures: the angle of R_gt^T R and the distance between the translations.
        const bool have_pose = matrix_is_finite(result.transform);
        json.field("rotation_error_deg", have_pose ? rotation_error_deg(result.transform, gt) : std::nan(""));
        json.field("translation_error_m", have_pose ? translation_error(result.transform, gt) : std::nan(""));
    }
    json.end_object();
    return json.str();
}

std::string batch_line_error(const PairRow &row, bool has_gt_column, const std::string &message) {
    JsonWriter json(true);
    add_common_fields(json, row, has_gt_column);
    json.field("status", "error");
    json.field("message", one_line(message));
    json.field("valid", false);
    json.key("transform");
    json.null();
    json.end_object();
    return json.str();
}

double batch_auto_voxel(const BatchRun &run, const std::vector<PairRow> &rows) {
    std::map<FeatureCache::Key, CloudPtr> clouds;
    for (const PairRow &row : rows)
        for (const FeatureCache::Key &key : {source_key(run, row), target_key(run, row)}) {
            if (clouds.count(key) != 0) continue;
            kissm_cloud *raw = nullptr;
            if (kissm_read_points(key.first.c_str(), key.second, &raw) != KISSM_OK) continue; // its pairs report it
            clouds.emplace(key, CloudPtr(raw));
        }
    // Only the clouds with a suggestion of their own take part: one without (no extent, too few points) fails its
    // own pairs, as it would with a voxel given, instead of the whole batch.
    std::vector<kissm_points> usable;
    for (const auto &entry : clouds) {
        kissm_points points{};
        double own = 0.0;
        if (kissm_cloud_points(entry.second.get(), &points) == KISSM_OK &&
            kissm_suggest_voxel_size(&points, 1, &own) == KISSM_OK)
            usable.push_back(points);
    }
    double voxel = 0.0;
    if (usable.empty() || kissm_suggest_voxel_size(usable.data(), usable.size(), &voxel) != KISSM_OK) return 0.0;
    return voxel;
}

BatchCounts run_batch_pairs(const BatchRun &run) {
    FeatureCache cache;
    for (const PairRow &row : run.pending) {
        cache.add_reference(source_key(run, row));
        cache.add_reference(target_key(run, row));
    }
    std::vector<MatcherPtr> matchers;
    const size_t jobs = std::min(static_cast<size_t>(run.jobs), std::max<size_t>(run.pending.size(), 1));
    for (size_t j = 0; j < jobs; ++j) {
        kissm_matcher *matcher = nullptr;
        const int32_t status = kissm_create(&run.config, &matcher);
        if (status != KISSM_OK) throw UsageError(settings_error(status));
        matchers.emplace_back(matcher);
    }
    ResultSink sink(run);
    std::atomic<size_t> next{0};
    const auto work = [&](kissm_matcher *matcher) {
        for (size_t i = next++; i < run.pending.size() && sink.ok(); i = next++) {
            const PairRow &row = run.pending[i];
            PairOutcome o;
            try {
                o = register_pair(run, row, cache, matcher);
            } catch (const std::bad_alloc &) {
                o = {batch_line_error(row, run.has_gt_column, "out of memory"), true, false};
            } catch (const std::exception &e) {
                o = {batch_line_error(row, run.has_gt_column, e.what()), true, false};
            }
            sink.add(o.line, o.error, o.valid);
            cache.release(source_key(run, row));
            cache.release(target_key(run, row));
        }
    };
    std::vector<std::thread> threads;
    for (size_t j = 1; j < jobs; ++j) threads.emplace_back(work, matchers[j].get());
    work(matchers[0].get()); // this thread is the first job
    for (std::thread &t : threads) t.join();
    return sink.finish();
}

} // namespace kissm_cli
