// SPDX-License-Identifier: MIT
//! Registers two point files and prints the result, like `kissm register`.
//!
//! ```text
//! cargo run --release --example register -- SRC TGT --voxel V [--threads N] [--json]
//!     [--format FMT | --format-src FMT --format-tgt FMT]
//! ```
//!
//! `--json` prints one JSON object with the same keys as the `kissm` tool's (`valid`, `reason`,
//! `reason_code`, `transform`, `rotation`, `translation`, `final_inliers`, `counts`, `inlier_ratio`,
//! `residual_rms`, `noise_bound`, `inlier_extent`, `time_ms`, plus `version`, `source`, `target`,
//! `voxel_size`, `threads`, `read_ms`). Every double reads back to the exact value (Rust's shortest
//! round-trip formatting); NaN is written as `null`. Exit status: 0 valid pose, 1 not valid, 2 usage or
//! input error.

use std::fmt::Write as _;
use std::process::ExitCode;
use std::time::Instant;

use kissm::{Config, Format, Matcher, Registration};

const USAGE: &str = "usage: register SRC TGT --voxel V [--threads N] [--json] \
                     [--format FMT | --format-src FMT --format-tgt FMT]\n\
                     FMT: auto, ply, pcd, kitti_bin, bin_xyz, npy or xyz";

struct Options {
    files: Vec<String>,
    voxel: Option<f64>,
    threads: usize,
    json: bool,
    source_format: Format,
    target_format: Format,
}

fn parse_args() -> Result<Options, String> {
    let mut opt = Options {
        files: Vec::new(),
        voxel: None,
        threads: 0,
        json: false,
        source_format: Format::Auto,
        target_format: Format::Auto,
    };
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        let mut value = |name: &str| args.next().ok_or_else(|| format!("{name} needs a value"));
        let format = |name: &str, text: String| {
            Format::from_name(&text).ok_or_else(|| format!("{name}: unknown format '{text}'"))
        };
        match arg.as_str() {
            "-h" | "--help" => return Err(String::new()),
            "--voxel" => {
                let text = value("--voxel")?;
                opt.voxel = Some(text.parse().map_err(|_| format!("--voxel: '{text}' is not a number"))?);
            }
            "--threads" => {
                let text = value("--threads")?;
                opt.threads = text.parse().map_err(|_| format!("--threads: '{text}' is not a count"))?;
            }
            "--json" => opt.json = true,
            "--format" => {
                let f = format("--format", value("--format")?)?;
                opt.source_format = f;
                opt.target_format = f;
            }
            "--format-src" => opt.source_format = format("--format-src", value("--format-src")?)?,
            "--format-tgt" => opt.target_format = format("--format-tgt", value("--format-tgt")?)?,
            _ if arg.starts_with('-') && arg.len() > 1 => return Err(format!("unknown option {arg}")),
            _ => opt.files.push(arg),
        }
    }
    if opt.files.len() != 2 {
        return Err(format!("expected 2 files (SRC TGT), got {}", opt.files.len()));
    }
    if opt.voxel.is_none() {
        return Err("--voxel V is required".to_string());
    }
    Ok(opt)
}

/// A JSON string literal.
fn json_string(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 || c == '\u{7f}' => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A JSON number that reads back to exactly `v` (Rust's `Display` for f64 is the shortest round-trip
/// form); `null` for NaN and infinities, like the C tool.
fn json_number(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        "null".to_string()
    }
}

fn json_row(values: &[f64]) -> String {
    let items: Vec<String> = values.iter().map(|&v| json_number(v)).collect();
    format!("[{}]", items.join(", "))
}

fn json_matrix<const N: usize>(rows: &[[f64; N]]) -> String {
    let items: Vec<String> = rows.iter().map(|r| json_row(r)).collect();
    format!("[{}]", items.join(", "))
}

/// `"key": value` lines of one object, comma-separated, at the given indentation.
fn json_object(fields: &[(&str, String)], indent: usize) -> String {
    let lines: Vec<String> =
        fields.iter().map(|(key, value)| format!("{:indent$}{}: {}", "", json_string(key), value)).collect();
    format!("{{\n{}\n{:close$}}}", lines.join(",\n"), "", close = indent - 2)
}

fn to_json(opt: &Options, reg: &Registration, read_ms: f64) -> String {
    let c = &reg.counts;
    let t = &reg.timings;
    let counts = [
        ("source_points", c.source_points),
        ("target_points", c.target_points),
        ("source_nonfinite", c.source_nonfinite),
        ("target_nonfinite", c.target_nonfinite),
        ("source_voxels", c.source_voxels),
        ("target_voxels", c.target_voxels),
        ("source_keypoints", c.source_keypoints),
        ("target_keypoints", c.target_keypoints),
        ("initial_correspondences", c.initial_correspondences),
        ("pruned_correspondences", c.pruned_correspondences),
        ("max_core_number", c.max_core_number),
        ("rotation_inliers", c.rotation_inliers),
        ("final_inliers", c.final_inliers),
    ]
    .map(|(key, value)| (key, value.to_string()));
    let times = [
        ("voxelize", t.voxelize_ms),
        ("features", t.features_ms),
        ("matching", t.matching_ms),
        ("pruning", t.pruning_ms),
        ("solver", t.solver_ms),
        ("total", t.total_ms),
    ]
    .map(|(key, value)| (key, json_number(value)));
    let fields = [
        ("version", json_string(kissm::version())),
        ("source", json_string(&opt.files[0])),
        ("target", json_string(&opt.files[1])),
        ("voxel_size", json_number(opt.voxel.unwrap_or(f64::NAN))),
        ("threads", opt.threads.to_string()),
        ("valid", reg.valid.to_string()),
        ("reason", json_string(reg.reason.as_str())),
        ("reason_code", reg.reason.code().to_string()),
        ("transform", json_matrix(&reg.transform)),
        ("rotation", json_matrix(&reg.rotation)),
        ("translation", json_row(&reg.translation)),
        ("final_inliers", reg.final_inliers().to_string()),
        ("counts", json_object(&counts, 4)),
        ("inlier_ratio", json_number(reg.inlier_ratio)),
        ("residual_rms", json_number(reg.residual_rms)),
        ("noise_bound", json_number(reg.noise_bound)),
        ("inlier_extent", json_row(&reg.inlier_extent)),
        ("time_ms", json_object(&times, 4)),
        ("read_ms", json_number(read_ms)),
    ];
    json_object(&fields, 2) + "\n"
}

fn print_summary(opt: &Options, reg: &Registration, read_ms: f64) {
    println!("kissm {} register (Rust)", kissm::version());
    println!("  source: {} ({} points)", opt.files[0], reg.counts.source_points);
    println!("  target: {} ({} points)", opt.files[1], reg.counts.target_points);
    println!("  voxel {}, threads {}, files read in {:.1} ms", opt.voxel.unwrap_or(f64::NAN), opt.threads, read_ms);
    println!("transform (maps source into target, row-major):");
    for row in &reg.transform {
        println!("  [ {:12.6} {:12.6} {:12.6} {:12.6} ]", row[0], row[1], row[2], row[3]);
    }
    if reg.valid {
        println!("valid: yes");
    } else {
        println!("valid: no (reason: {})", reg.reason);
    }
    let c = &reg.counts;
    println!(
        "keypoints {} / {}, matches {}, pruned {}, final inliers {}",
        c.source_keypoints, c.target_keypoints, c.initial_correspondences, c.pruned_correspondences, c.final_inliers
    );
    println!("time: {:.1} ms", reg.timings.total_ms);
}

fn run(opt: &Options) -> Result<Registration, kissm::Error> {
    let config = Config::builder().voxel_size(opt.voxel.unwrap_or(f64::NAN)).num_threads(opt.threads).build()?;
    let read_start = Instant::now();
    let source = kissm::read_points_with_format(&opt.files[0], opt.source_format)?;
    let target = kissm::read_points_with_format(&opt.files[1], opt.target_format)?;
    let read_ms = read_start.elapsed().as_secs_f64() * 1e3;
    let mut matcher = Matcher::new(&config)?;
    let reg = matcher.register(&source, &target)?;
    if opt.json {
        print!("{}", to_json(opt, &reg, read_ms));
    } else {
        print_summary(opt, &reg, read_ms);
    }
    Ok(reg)
}

fn main() -> ExitCode {
    let opt = match parse_args() {
        Ok(opt) => opt,
        Err(message) if message.is_empty() => {
            println!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        Err(message) => {
            eprintln!("register: {message}\n{USAGE}");
            return ExitCode::from(2);
        }
    };
    match run(&opt) {
        Ok(reg) if reg.valid => ExitCode::SUCCESS,
        Ok(_) => ExitCode::from(1),
        Err(e) => {
            eprintln!("register: {e}");
            ExitCode::from(2)
        }
    }
}
