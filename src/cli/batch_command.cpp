// SPDX-License-Identifier: MIT
// kissm batch PAIRS.tsv --voxel V --out RESULTS.jsonl [--jobs N] [--resume] [register's options]
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include <kissm.h>

#include "batch/batch_pairs.hpp"
#include "batch/batch_progress.hpp"
#include "batch/batch_resume.hpp"
#include "batch/batch_run.hpp"
#include "cli_args.hpp"
#include "commands.hpp"
#include "pair_command.hpp"

namespace kissm_cli {
namespace {

struct BatchOptions {
    PairOptions pair; // register's settings; pair.files holds the pairs file
    std::string out;
    int32_t jobs = 1;
    bool resume = false;
    bool quiet = false;
};

bool parse_batch_options(const std::vector<std::string> &args, BatchOptions *out) {
    BatchOptions opt;
    opt.pair.refine_mode = KISSM_REFINE_NONE;
    ArgCursor cur("batch", args);
    while (cur.next()) {
        const std::string name = cur.current();
        if (!cur.is_option()) {
            opt.pair.files.push_back(name);
        } else if (cur.is_help()) {
            print_batch_help(stdout);
            return false;
        } else if (name == "--out") {
            opt.out = cur.value();
        } else if (name == "--jobs") {
            opt.jobs = parse_int32(name, cur.value(), 1, 1024);
        } else if (!cur.take_flag("--resume", &opt.resume) && !cur.take_flag("--quiet", &opt.quiet, "-q") &&
                   !take_pair_option(PairCommand::Register, cur, false, &opt.pair)) {
            cur.unknown();
        }
    }
    const std::string see = " (see 'kissm batch --help')";
    if (opt.pair.files.size() != 1) {
        throw UsageError("batch expects 1 pairs file, got " + std::to_string(opt.pair.files.size()) + see);
    }
    require_voxel("batch", opt.pair);
    if (opt.out.empty()) throw UsageError("batch needs --out FILE, the results (one JSON line per pair)" + see);
    *out = opt;
    return true;
}

bool exists_non_empty(const std::string &path) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    return !ec && size > 0;
}

int run_batch_command(const BatchOptions &given) {
    BatchOptions opt = given;
    // One matcher thread per job unless --threads says otherwise: the jobs are the parallelism.
    if (!opt.pair.have_threads) opt.pair.threads = 1;
    const kissm_config config = pair_config(PairCommand::Register, opt.pair);
    const std::string &pairs_file = opt.pair.files[0];
    const PairsTable table = read_pairs_file(pairs_file);

    if (!opt.resume && exists_non_empty(opt.out)) {
        throw UsageError("'" + one_line(opt.out) +
                         "' exists and is not empty: --resume completes it, or remove it to start again");
    }
    const std::vector<DoneRecord> done =
        opt.resume ? resume_results(opt.out, table.rows, "pairs file", opt.quiet) : std::vector<DoneRecord>();
    std::vector<bool> is_done(table.rows.size(), false);
    BatchCounts earlier;
    for (const DoneRecord &d : done) {
        is_done[static_cast<size_t>(d.pair - 1)] = true;
        size_t &count = d.error ? earlier.errors : (d.valid ? earlier.valid : earlier.invalid);
        ++count;
    }

    BatchRun run;
    run.config = config;
    run.source_format = opt.pair.source_format;
    run.target_format = opt.pair.target_format;
    run.pairs_file = pairs_file;
    run.has_gt_column = table.has_gt_column;
    // --voxel auto: one voxel for every cloud of the file (all rows, so that --resume continues with the same one).
    if (opt.pair.voxel_auto) run.config.voxel_size = batch_auto_voxel(run, table.rows);
    for (const PairRow &row : table.rows) {
        if (!is_done[static_cast<size_t>(row.index - 1)]) run.pending.push_back(row);
    }
    run.jobs = opt.jobs;
    run.progress = !opt.quiet;
    run.out_name = opt.out;
    std::FILE *file = std::fopen(opt.out.c_str(), "ab");
    if (!file) throw UsageError("cannot write the results to '" + one_line(opt.out) + "'");
    // A buffer larger than any line, so that each line leaves in one write.
    std::setvbuf(file, nullptr, _IOFBF, 1 << 16);
    run.out = file;

    const auto start = std::chrono::steady_clock::now();
    BatchCounts now;
    try {
        now = run_batch_pairs(run);
    } catch (...) {
        std::fclose(file);
        throw;
    }
    if (std::fclose(file) != 0) throw UsageError("cannot write the results to '" + one_line(opt.out) + "'");
    const double seconds = elapsed_ms(start) / 1000.0;

    const size_t ran = run.pending.size();
    const size_t valid = earlier.valid + now.valid, invalid = earlier.invalid + now.invalid;
    const size_t errors = earlier.errors + now.errors;
    if (!opt.quiet) {
        std::fprintf(stderr, "kissm batch: %zu pairs: %zu valid, %zu not valid, %zu error%s", table.rows.size(), valid,
                     invalid, errors, errors == 1 ? "" : "s");
        if (!done.empty()) std::fprintf(stderr, " (%zu done by an earlier run)", done.size());
        std::fprintf(stderr, "; ran %zu in %.2f s (%.3g pairs/s); results in %s\n", ran, seconds,
                     seconds > 0.0 ? static_cast<double>(ran) / seconds : 0.0, opt.out.c_str());
    }
    return errors > 0 ? kExitInvalid : kExitOk;
}

} // namespace

void print_batch_help(std::FILE *out) {
    std::fprintf(out,
                 "usage: kissm batch PAIRS.tsv --voxel V --out RESULTS.jsonl [--jobs N] [--resume] [options]\n"
                 "\n"
                 "Registers every pair of a pairs file, as `kissm register` would, describing each distinct cloud\n"
                 "once, and appends one JSON line per pair to RESULTS.jsonl as it finishes.\n"
                 "\n"
                 "PAIRS.tsv: tab-separated; the first line that is neither blank nor a '#' comment names the\n"
                 "columns: source and target (required), gt (optional: a 4x4 ground-truth transform file, 4 rows\n"
                 "of 4 numbers, mapping source into target), format (optional: a --format name for both clouds\n"
                 "of the row, over --format; empty: the run's); other columns are ignored. Relative paths are\n"
                 "resolved against the pairs file's folder. The pairs are numbered 1, 2, ... in file order.\n"
                 "\n"
                 "Batch options:\n"
                 "  --out FILE              the results, one JSON object per line (required). An existing\n"
                 "                          non-empty FILE is refused unless --resume\n"
                 "  --resume                skip the pairs FILE already holds (by their \"pair\" number) and append\n"
                 "                          the others; a partial last line (a killed run) is dropped first. Without\n"
                 "                          FILE it just runs\n"
                 "  --jobs N                pairs registered at once, each by its own matcher, 1..1024 (default 1)\n"
                 "  --threads N             each job's worker threads (default 1 here; 0 = all hardware threads)\n"
                 "  -q, --quiet             no progress line and no summary on stderr\n"
                 "\n"
                 "Registration: every option of `kissm register` but the output ones (--json, --out-*): --voxel\n"
                 "or --preset, --refine, --suppression, --rotation-dof, --up, --min-inliers, ... ('kissm register\n"
                 "--help'); --format, --format-src, --format-tgt apply to every pair without a format of its own.\n"
                 "\n"
                 "Each line: pair, source, target (as written in PAIRS.tsv), gt (with a gt column; null when the\n"
                 "row's is empty), status, then with status \"ok\" the fields of `register --json` but time_ms\n"
                 "(valid, reason, transform, ...) and, with gt, rotation_error_deg and translation_error_m; with\n"
                 "status \"error\" (a cloud or gt file that cannot be read, ...) message, valid false and transform\n"
                 "null. A pair's line holds no timing: it is the same bytes at any --jobs and after --resume. The\n"
                 "lines are in the order the pairs finish. Progress (rate, ETA) and the summary go to stderr.\n"
                 "\n"
                 "Exit status: 0 every pair ran (valid or not), 1 some pairs are \"error\" lines (the others ran),\n"
                 "2 usage or input error (bad options, unreadable pairs file or header, --out exists without\n"
                 "--resume, or --out is not a batch results file of this pairs file); nothing is run then.\n");
}

int run_batch(const std::vector<std::string> &args) {
    BatchOptions opt;
    if (!parse_batch_options(args, &opt)) return kExitOk;
    return run_batch_command(opt);
}

} // namespace kissm_cli
