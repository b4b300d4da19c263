// SPDX-License-Identifier: MIT
// kissm align SCANS.tsv --voxel V --out POSES.tsv [--pairs all|sequence|FILE] [--jobs N] [--resume] [outputs]
// [register's options]: the pairs registered by `kissm batch`'s runner into a results file, then a pose graph of
// the valid ones (align/), as Python's kissm.multiway.align.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <set>
#include <string>
#include <vector>

#include <kissm.h>

#include "align/align_graph.hpp"
#include "align/align_map.hpp"
#include "align/align_pairs.hpp"
#include "align/align_priors.hpp"
#include "align/align_scans.hpp"
#include "align/align_similar.hpp"
#include "align/align_writers.hpp"
#include "batch/batch_pairs.hpp"
#include "batch/batch_resume.hpp"
#include "batch/batch_run.hpp"
#include "cli_args.hpp"
#include "commands.hpp"
#include "json_writer.hpp"
#include "pair_command.hpp"
#include "report.hpp"

namespace kissm_cli {
namespace {

struct AlignOptions {
    PairOptions pair; // register's settings; pair.files holds the scans file
    std::string out, results, map, g2o, tum, kitti, priors;
    std::string pairs = "all"; // all, sequence, sessions or a pairs file
    int32_t stride = 10;       // sessions: the grid across sessions
    bool have_window = false;
    bool have_stride = false;
    bool have_loop_radius = false;
    bool have_similar = false;
    std::string loop_option; // the first loop option given, for the message when --pairs is not sequence
    SequenceOptions sequence;
    double map_voxel = 0.0; // 0: every point
    double bound = KISSM_POSE_GRAPH_DEFAULT_BOUND;
    int32_t jobs = 1;
    bool resume = false;
    bool quiet = false;
};

bool parse_align_options(const std::vector<std::string> &args, AlignOptions *out) {
    AlignOptions opt;
    // GICP by default, as Python's multiway.align: its information weighs the edges.
    opt.pair.refine_mode = KISSM_REFINE_GICP;
    ArgCursor cur("align", args);
    while (cur.next()) {
        const std::string name = cur.current();
        if (!cur.is_option()) {
            opt.pair.files.push_back(name);
        } else if (cur.is_help()) {
            print_align_help(stdout);
            return false;
        } else if (name == "--out") {
            opt.out = cur.value();
        } else if (name == "--results") {
            opt.results = cur.value();
        } else if (name == "--pairs") {
            opt.pairs = cur.value();
            if (opt.pairs.empty()) throw UsageError("--pairs: expected all, sequence or a pairs file");
        } else if (name == "--stride") {
            opt.stride = parse_int32(name, cur.value(), 1, 1000000);
            opt.have_stride = true;
        } else if (name == "--window") {
            opt.sequence.window = parse_int32(name, cur.value(), 1, 1000000);
            opt.have_window = true;
        } else if (name == "--loop-gap") {
            opt.sequence.loop_gap = parse_int32(name, cur.value(), 1, 1000000);
            if (opt.loop_option.empty()) opt.loop_option = name;
        } else if (name == "--loops-per-scan") {
            opt.sequence.loops_per_scan = parse_int32(name, cur.value(), 0, 1000000);
            if (opt.loop_option.empty()) opt.loop_option = name;
        } else if (name == "--similar-per-scan") {
            opt.sequence.similar_per_scan = parse_int32(name, cur.value(), 0, 1000000);
            opt.have_similar = true;
        } else if (name == "--loop-radius") {
            opt.sequence.loop_radius = parse_positive(name, cur.value());
            opt.have_loop_radius = true;
            if (opt.loop_option.empty()) opt.loop_option = name;
        } else if (name == "--priors") {
            opt.priors = cur.value();
            if (opt.priors.empty()) throw UsageError("--priors: expected a file (the poses table layout of --out)");
            if (opt.loop_option.empty()) opt.loop_option = name;
        } else if (name == "--map") {
            opt.map = cur.value();
        } else if (name == "--map-voxel") {
            opt.map_voxel = parse_positive(name, cur.value());
        } else if (name == "--g2o") {
            opt.g2o = cur.value();
        } else if (name == "--tum") {
            opt.tum = cur.value();
        } else if (name == "--kitti") {
            opt.kitti = cur.value();
        } else if (name == "--bound") {
            opt.bound = parse_positive(name, cur.value());
        } else if (name == "--jobs") {
            opt.jobs = parse_int32(name, cur.value(), 1, 1024);
        } else if (!cur.take_flag("--resume", &opt.resume) && !cur.take_flag("--quiet", &opt.quiet, "-q") &&
                   !take_pair_option(PairCommand::Register, cur, false, &opt.pair)) {
            cur.unknown();
        }
    }
    const std::string see = " (see 'kissm align --help')";
    if (opt.pair.files.size() != 1) {
        throw UsageError("align expects 1 scans file, got " + std::to_string(opt.pair.files.size()) + see);
    }
    require_voxel("align", opt.pair);
    if (opt.out.empty()) throw UsageError("align needs --out FILE, the poses (one line per scan)" + see);
    if (opt.have_window && opt.pairs != "sequence") throw UsageError("--window applies to --pairs sequence only");
    const bool sessions = opt.pairs == "sessions";
    if (opt.have_stride && !sessions) throw UsageError("--stride applies to --pairs sessions only");
    if (!opt.loop_option.empty() && opt.pairs != "sequence" && !(sessions && opt.loop_option != "--priors")) {
        throw UsageError(opt.loop_option + " applies to --pairs sequence" +
                         (opt.loop_option == "--priors" ? std::string(" only") : std::string(" and sessions only")));
    }
    if (opt.pairs == "sequence" && opt.sequence.loops_per_scan > 0 && opt.sequence.window > 1 &&
        opt.sequence.window >= opt.sequence.loop_gap) {
        throw UsageError("--window " + std::to_string(opt.sequence.window) +
                         " with loop candidates needs --loop-gap above " + std::to_string(opt.sequence.window) +
                         " (a candidate would repeat a window pair), or --loops-per-scan 0");
    }
    if (opt.have_similar && opt.pairs != "sequence")
        throw UsageError("--similar-per-scan applies to --pairs sequence only");
    if (opt.have_similar && !opt.priors.empty())
        throw UsageError("--similar-per-scan applies without --priors only (the priors relate every scan)");
    if (opt.map_voxel > 0.0 && opt.map.empty()) throw UsageError("--map-voxel needs --map FILE");
    // Every scan is a source of some pair and a target of another: one format for all.
    if (opt.pair.source_format != opt.pair.target_format) {
        throw UsageError("align: --format-src and --format-tgt do not apply (every scan is both); use --format or the "
                         "scans file's format column");
    }
    if (opt.results.empty()) opt.results = opt.out + ".pairs.jsonl";
    const std::string results = std::filesystem::path(opt.results).lexically_normal().string();
    if (!opt.priors.empty() &&
        std::filesystem::path(opt.priors).lexically_normal() == std::filesystem::path(opt.out).lexically_normal()) {
        throw UsageError("--priors and --out are both '" + one_line(opt.out) +
                         "': the poses would overwrite the priors; give --out another name");
    }
    for (const std::string *output : {&opt.out, &opt.map, &opt.g2o, &opt.tum, &opt.kitti}) {
        if (!output->empty() && std::filesystem::path(*output).lexically_normal().string() == results) {
            throw UsageError("'" + one_line(*output) + "' is the results file too; give the outputs other names");
        }
    }
    *out = opt;
    return true;
}

std::vector<ScanPair> chosen_pairs(const AlignOptions &opt, const std::vector<Scan> &scans) {
    if (opt.pairs == "all") return all_pairs(scans.size());
    if (opt.pairs == "sequence") return sequence_candidates(scans.size(), opt.sequence);
    if (opt.pairs == "sessions") return session_odometry(session_starts(scans));
    return pairs_from_file(opt.pairs, scans);
}

bool exists_non_empty(const std::string &path) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    return !ec && size > 0;
}

// Every record of the results file, with the poses the graph needs (none when the file does not exist and
// `missing_ok`).
std::vector<DoneRecord> read_all_records(const std::string &path, bool missing_ok = false) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        if (missing_ok) return {};
        throw UsageError("cannot read the pair results '" + one_line(path) + "'");
    }
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    return scan_results(text, "'" + one_line(path) + "'", true).done;
}

// The records of pairs 1..rows.size() the results file holds (--resume, checked against `rows`: a record beyond
// them or of another pair is a UsageError, the file untouched; a partial last line is cut off).
std::vector<bool> done_pairs(const AlignOptions &opt, const std::vector<PairRow> &rows) {
    std::vector<bool> is_done(rows.size(), false);
    if (!opt.resume) return is_done;
    for (const DoneRecord &d : resume_results(opt.results, rows, "pair list", opt.quiet)) {
        is_done[static_cast<size_t>(d.pair - 1)] = true;
    }
    return is_done;
}

// Registers rows[from..] that are not done, appending their lines to the results file (batch's runner and
// format). Returns how many ran.
size_t register_pending(const AlignOptions &opt, const kissm_config &config, const std::vector<PairRow> &rows,
                        const std::vector<bool> &is_done, size_t from = 0) {
    BatchRun run;
    run.config = config;
    run.pairs_file = opt.pair.files[0];
    for (size_t k = from; k < rows.size(); ++k) {
        if (k >= is_done.size() || !is_done[k]) run.pending.push_back(rows[k]);
    }
    run.jobs = opt.jobs;
    run.progress = !opt.quiet;
    run.progress_label = "kissm align";
    run.out_name = opt.results;
    std::FILE *file = std::fopen(opt.results.c_str(), "ab");
    if (!file) throw UsageError("cannot write the pair results to '" + one_line(opt.results) + "'");
    std::setvbuf(file, nullptr, _IOFBF, 1 << 16); // each line leaves in one write, as batch's
    run.out = file;
    try {
        run_batch_pairs(run);
    } catch (...) {
        std::fclose(file);
        throw;
    }
    if (std::fclose(file) != 0) throw UsageError("cannot write the pair results to '" + one_line(opt.results) + "'");
    return run.pending.size();
}

// The later rounds of a policy: each gives its pairs from the records of all the pairs before it (so_far), which
// are all in the results file by then.
using NextRound = std::function<std::vector<ScanPair>(const std::vector<DoneRecord> &, const std::vector<ScanPair> &)>;

// A sequence without priors takes candidates by similarity where its chain breaks (--similar-per-scan).
bool takes_similar(const AlignOptions &opt) {
    return opt.pairs == "sequence" && opt.sequence.priors.empty() && opt.sequence.similar_per_scan > 0;
}

std::vector<NextRound> later_rounds(const AlignOptions &opt, const kissm_config &config, const std::vector<Scan> &scans,
                                    const std::vector<ScanPair> &round1) {
    std::vector<NextRound> rounds;
    if (opt.pairs == "sequence" && (opt.sequence.loops_per_scan > 0 || takes_similar(opt))) {
        rounds.push_back(
            [&opt, &config, &scans, round1](const std::vector<DoneRecord> &records, const std::vector<ScanPair> &) {
                const std::vector<ScanPair> loops = sequence_loops(scans.size(), round1, records, opt.sequence);
                if (!takes_similar(opt)) return loops;
                const SequenceChain chain = sequence_chain(scans.size(), round1, records);
                if (!chain_breaks(chain)) return loops; // an unbroken chain needs no signatures
                // The signatures depend on the scans alone: a resumed run finds the same candidates. Described on the
                // --jobs threads (the bits do not depend on their number).
                kissm_config describe = config;
                describe.num_threads = opt.jobs;
                const std::vector<double> signatures = scan_signatures(scans, describe);
                return merged_loops(loops, similar_loops(chain, signatures, opt.sequence));
            });
    }
    if (opt.pairs == "sessions") {
        const std::vector<size_t> starts = session_starts(scans);
        rounds.push_back([&opt, starts, round1](const std::vector<DoneRecord> &records, const std::vector<ScanPair> &) {
            return session_loops_and_grid(starts, round1, records, opt.sequence, static_cast<size_t>(opt.stride));
        });
        rounds.push_back([&opt, starts](const std::vector<DoneRecord> &records, const std::vector<ScanPair> &so_far) {
            const Alignment a = solve_alignment(starts.back(), so_far, records, opt.bound);
            return sessions_across(starts, so_far, a.poses, a.placed, opt.sequence);
        });
    }
    return rounds;
}

bool all_recorded(const std::vector<ScanPair> &pairs, const std::vector<DoneRecord> &records) {
    std::vector<bool> seen(pairs.size(), false);
    for (const DoneRecord &d : records) {
        if (d.pair >= 1 && d.pair <= static_cast<int64_t>(pairs.size())) seen[static_cast<size_t>(d.pair - 1)] = true;
    }
    return std::find(seen.begin(), seen.end(), false) == seen.end();
}

// Registers the pairs the results file does not hold yet, round by round: round 1's pairs (1..n1), then each later
// round's (numbered after the pairs before it), appended to *pairs. A round's list depends on the records before
// it only: a resumed run finds the lists of the rounds whose earlier pairs are all in the file before it checks
// the file, and completes the rest in order. Returns how many ran.
size_t register_all(const AlignOptions &opt, const kissm_config &config, const std::vector<Scan> &scans,
                    std::vector<ScanPair> *pairs) {
    if (!opt.resume && exists_non_empty(opt.results)) {
        throw UsageError("'" + one_line(opt.results) +
                         "' exists and is not empty: --resume completes it, or remove it to start again");
    }
    const std::vector<NextRound> rounds = later_rounds(opt, config, scans, *pairs);
    size_t round = 0;
    if (opt.resume) {
        const std::vector<DoneRecord> records = read_all_records(opt.results, true);
        // The names are checked with the rows below (resume_results).
        for (; round < rounds.size() && all_recorded(*pairs, records); ++round) {
            const std::vector<ScanPair> next = rounds[round](records, *pairs);
            pairs->insert(pairs->end(), next.begin(), next.end());
        }
    }
    std::vector<PairRow> rows = pair_rows(*pairs, scans);
    size_t ran = register_pending(opt, config, rows, done_pairs(opt, rows));
    for (; round < rounds.size(); ++round) {
        const size_t from = pairs->size();
        const std::vector<ScanPair> next = rounds[round](read_all_records(opt.results), *pairs);
        pairs->insert(pairs->end(), next.begin(), next.end());
        rows = pair_rows(*pairs, scans);
        if (!next.empty()) ran += register_pending(opt, config, rows, {}, from);
    }
    return ran;
}

// --voxel auto: one voxel for every scan together (kissm_suggest_voxel_size of them all), as kissm.multiway.align
// resolves "auto": every pair, the loop radius and a resumed run need the same voxel, which per-pair suggestions
// would not give. Every scan is read once for it.
double scans_auto_voxel(const std::vector<Scan> &scans) {
    std::vector<CloudPtr> clouds;
    std::vector<kissm_points> points;
    clouds.reserve(scans.size());
    for (const Scan &scan : scans) {
        clouds.push_back(read_cloud("scan", scan.file, scan.format));
        points.push_back(points_of(clouds.back().get(), "scan"));
    }
    double voxel = 0.0;
    const int32_t status = kissm_suggest_voxel_size(points.data(), points.size(), &voxel);
    if (status != KISSM_OK) throw UsageError("--voxel auto: " + library_error(status));
    return voxel;
}

int run_align_command(const AlignOptions &given) {
    AlignOptions opt = given;
    // One matcher thread per job unless --threads says otherwise: the jobs are the parallelism.
    if (!opt.pair.have_threads) opt.pair.threads = 1;
    kissm_config config = pair_config(PairCommand::Register, opt.pair);
    const std::vector<Scan> scans = read_scans_file(opt.pair.files[0], opt.pair.source_format);
    if (opt.pair.voxel_auto) config.voxel_size = scans_auto_voxel(scans);
    if ((opt.pairs == "sequence" || opt.pairs == "sessions") && !opt.have_loop_radius)
        opt.sequence.loop_radius = 30.0 * config.voxel_size;
    if (opt.pairs == "sessions" &&
        std::any_of(scans.begin(), scans.end(), [](const Scan &s) { return s.session.empty(); }))
        throw UsageError("--pairs sessions needs a session column in the scans file, with a session for every scan");
    if (!opt.priors.empty()) opt.sequence.priors = read_priors(opt.priors, scans);
    std::vector<ScanPair> pairs = chosen_pairs(opt, scans);

    const auto start = std::chrono::steady_clock::now();
    const size_t ran = register_all(opt, config, scans, &pairs);
    const double seconds = elapsed_ms(start) / 1000.0;

    // The graph is built from every record, in pair order: the same poses after a resume and at any --jobs.
    const std::vector<DoneRecord> records = read_all_records(opt.results);
    std::vector<uint8_t> held_out;
    if (takes_similar(opt)) {
        const size_t round1 = sequence_candidates(scans.size(), opt.sequence).size();
        const std::vector<ScanPair> first(pairs.begin(), pairs.begin() + static_cast<std::ptrdiff_t>(round1));
        held_out = held_out_pairs(sequence_chain(scans.size(), first, records), pairs, records, opt.sequence);
    }
    const Alignment a = solve_alignment(scans.size(), pairs, records, opt.bound, held_out);
    if (!opt.quiet) {
        for (const std::string &message : a.skipped) std::fprintf(stderr, "kissm: align: %s\n", message.c_str());
    }
    write_text_file(opt.out, poses_table(scans, a), "--out");
    if (!opt.tum.empty()) write_text_file(opt.tum, tum_text(a), "--tum");
    if (!opt.kitti.empty()) write_text_file(opt.kitti, kitti_text(a), "--kitti");
    if (!opt.g2o.empty()) write_text_file(opt.g2o, g2o_text(a), "--g2o");
    if (!opt.map.empty()) write_merged_map(opt.map, scans, a, opt.map_voxel);

    size_t placed = 0, accepted = 0;
    std::set<uint64_t> components;
    for (size_t k = 0; k < scans.size(); ++k) {
        placed += a.placed[k] ? 1 : 0;
        components.insert(a.components[k]);
    }
    for (const AlignEdge &edge : a.edges) accepted += edge.accepted ? 1 : 0;
    if (!opt.quiet) {
        std::fprintf(stderr,
                     "kissm align: %zu scans: %zu placed, %zu component%s; %zu pairs: %zu valid (%zu edges accepted, "
                     "%zu rejected), %zu not valid, %zu error%s; ran %zu in %.2f s; poses in %s\n",
                     scans.size(), placed, components.size(), components.size() == 1 ? "" : "s", pairs.size(), a.valid,
                     accepted, a.edges.size() - accepted, a.invalid, a.errors, a.errors == 1 ? "" : "s", ran, seconds,
                     opt.out.c_str());
    }
    return placed == scans.size() ? kExitOk : kExitInvalid;
}

} // namespace

void print_align_help(std::FILE *out) {
    std::fprintf(
        out,
        "usage: kissm align SCANS.tsv --voxel V --out POSES.tsv [--pairs all|sequence|sessions|FILE]\n"
        "                   [--jobs N]\n"
        "                   [--resume] [--map MAP.ply] [--g2o G.g2o] [options]\n"
        "\n"
        "Puts many scans into the first one's frame with no initial guess: registers the chosen pairs as\n"
        "`kissm batch` does (each scan described once, --jobs at a time, one JSON line per pair kept in a\n"
        "results file so that a killed run resumes), makes every valid registration a robust edge of a\n"
        "pose graph (its transform and information) and optimises it from the first scan. A scan that\n"
        "accepted edges do not join to the first one is reported as not placed, never given a guess.\n"
        "The same settings give the same poses as Python's kissm.multiway.align, bit for bit.\n"
        "\n"
        "SCANS.tsv: tab-separated; blank and '#' lines ignored; the first other line names the columns:\n"
        "scan (a name) and file (relative to SCANS.tsv's folder, or absolute) required, format optional\n"
        "(%s;\n"
        "empty = --format's, default auto) and session (for --pairs sessions) optional; other columns are\n"
        "ignored.\n"
        "\n"
        "Align options:\n"
        "  --out FILE              the poses (required): a header line, then per scan in SCANS.tsv's order\n"
        "                          scan, placed (1/0), component (the smallest scan position joined to\n"
        "                          it; 0 when placed), T00 ... T23: the first 3 rows of T_world_scan\n"
        "                          (world = the first scan's frame), shortest round-trip numbers, nan\n"
        "                          where not placed\n"
        "  --pairs all|sequence|sessions|FILE  the pairs registered (default all): all = every pair once, the\n"
        "                          later scan the source; sequence = scans in acquisition order: each\n"
        "                          with the --window K scans after it (default 1: consecutive pairs),\n"
        "                          then loop candidates (below); FILE = a tab-separated file with\n"
        "                          source and target columns naming scans (blank and '#' ignored)\n"
        "                          sessions = the scans file's session column groups the scans into\n"
        "                          sessions (drives, robots, days; each session's scans together, in\n"
        "                          acquisition order), merged as Python's align_sessions: each\n"
        "                          session's consecutive pairs trusted, its loop candidates, a grid of\n"
        "                          every --stride-th scan across sessions, then each placed scan with\n"
        "                          the nearest placed scans of earlier sessions (a third round)\n"
        "  --stride N              sessions: the grid across sessions, 1..1000000 (default 10)\n"
        "  --window K              for --pairs sequence, 1..1000000 (default 1); above 1 with loop\n"
        "                          candidates, below --loop-gap (dead reckoning chains the k+1 -> k\n"
        "                          pairs only)\n"
        "  --loop-gap N            sequence: a loop candidate's scans are at least N apart (default 10)\n"
        "  --loops-per-scan N      sequence: at most N loop candidates per scan, the nearest (default 5;\n"
        "                          0 = none: the first round only)\n"
        "  --loop-radius R         sequence: candidates lie within R of each other (default 30 x the\n"
        "                          voxel), plus 2%% of the path between them (none with --priors)\n"
        "  --similar-per-scan N    sequence without --priors: where the chain of consecutive registrations\n"
        "                          breaks into pieces, each scan's N earlier scans of other pieces (at\n"
        "                          least --loop-gap back) with the nearest signatures are candidates too,\n"
        "                          and of the valid pairs between two pieces only the largest set that\n"
        "                          agrees joins the graph (default 3; 0 = none)\n"
        "  --priors FILE           sequence: loop candidates from these world <- scan poses (GNSS, a SLAM\n"
        "                          run, an earlier --out) instead of the chained registrations: the\n"
        "                          poses table layout of --out (scan and T00 ... T23 columns); a scan\n"
        "                          without a row or with nan numbers has no prior and no candidates\n"
        "  --results FILE          the pair results, `kissm batch`'s lines named by scan (default\n"
        "                          POSES.tsv.pairs.jsonl). An existing non-empty FILE is refused unless\n"
        "                          --resume\n"
        "  --resume                keep FILE's finished pairs, run the others; the poses are the same\n"
        "                          bytes as an uninterrupted run's\n"
        "  --jobs N                pairs registered at once, 1..1024 (default 1)\n"
        "  --threads N             each job's worker threads (default 1 here; 0 = all hardware threads)\n"
        "  --map FILE.ply          the placed scans' points in the world frame (binary PLY)\n"
        "  --map-voxel V           with --map: one centroid per occupied voxel of size V instead\n"
        "  --g2o FILE              the graph in g2o's format (placed scans, accepted edges)\n"
        "  --tum FILE              the placed scans' poses in the TUM format (the position as timestamp)\n"
        "  --kitti FILE            every scan's pose in the KITTI format (nan where not placed)\n"
        "  --bound B               the pose graph's rejection bound on an edge's squared error\n"
        "                          (default %g, the 99.9%% chi-square quantile for 6 dof)\n"
        "  -q, --quiet             no progress line and no summary on stderr\n"
        "\n"
        "Loop candidates (Python's pairs=\"sequence\", the library's kissm_sequence_loops): the valid\n"
        "consecutive registrations (scan k+1 into k) chained into dead-reckoned positions (an invalid or\n"
        "missing one starts a new piece), or the --priors' positions; then for each scan j, the scans\n"
        "i <= j - N of its piece within R (+ 2%% of the path from i to j when dead-reckoned), the\n"
        "--loops-per-scan nearest, are registered in a second round (pairs numbered after the first's)\n"
        "and join the graph after the first round's edges. Without --priors, where the chain breaks, the\n"
        "--similar-per-scan scans of other pieces with the nearest signatures (kissm_sequence_similar:\n"
        "each scan described once more, on --jobs threads) join that round, and a valid pair between\n"
        "two pieces outside the largest set that agrees (kissm_sequence_corroborated) is reported as a\n"
        "rejected edge and left out of the graph.\n"
        "\n"
        "Registration: every option of `kissm register` but the output ones, as in `kissm batch`:\n"
        "--voxel or --preset (--voxel auto: one voxel for all the scans, suggested from them together),\n"
        "--refine (default gicp here: its information weighs the edges; with\n"
        "none, an edge's information comes from its rotation uncertainty and noise bound), the validity\n"
        "settings, --suppression, --rotation-dof, --up, ... ('kissm register --help'); --format applies\n"
        "to the scans without a format (--format-src and --format-tgt do not apply).\n"
        "\n"
        "Progress (pairs, rate, ETA) and a summary (scans placed, components, edges accepted and\n"
        "rejected) go to stderr; nothing to stdout.\n"
        "\n"
        "Exit status: 0 every scan placed, 1 some scans not placed (the outputs are still written),\n"
        "2 usage or input error (bad options, an unreadable or malformed scans or pairs file, an unknown\n"
        "scan, the results file exists without --resume or holds another pair list's results).\n",
        format_names(), KISSM_POSE_GRAPH_DEFAULT_BOUND);
}

int run_align(const std::vector<std::string> &args) {
    AlignOptions opt;
    if (!parse_align_options(args, &opt)) return kExitOk;
    return run_align_command(opt);
}

} // namespace kissm_cli
