// SPDX-License-Identifier: MIT
//! Registers two point files and prints the result, like `kissm register`; with `--initial T.txt`, refines
//! that transform instead, like `kissm refine SRC TGT --initial T.txt`.
//!
//! ```text
//! cargo run --release --example register -- SRC TGT --voxel V|auto [--threads N] [--json]
//!     [--refine gicp|point-to-plane|none] [--initial T.txt]
//!     [--format FMT | --format-src FMT --format-tgt FMT]
//! ```
//!
//! `--refine` refines the solver's pose (default `none`); with `--initial` it picks the cost (default
//! `gicp`; `none` is refused there). `T.txt` is 4 rows of 4 whitespace-separated numbers (lines starting
//! with `#` ignored), as `kissm register --out-transform` writes it.
//!
//! `--json` prints the object `kissm register --json` (or `kissm refine --json`) prints, byte for byte but
//! for the times: the same keys in the same order (`version`, `source`, `target`, `voxel_size`,
//! `threads`, `valid`, `reason`, `reason_code`, `initial_transform` with `--initial`, `transform`,
//! `rotation`, `translation`, `coarse_transform`, `refine`, `information`, `overlap`, `refine_rmse`,
//! `refine_condition`, `degenerate`, `weak_directions` (the rows in use: `[]` when none), `inlier_coverage`,
//! `refine_iterations`, `refine_converged`, `final_inliers`, `voxel_size_used`, `counts` (with `source_suppressed`,
//! `target_suppressed`), `inlier_ratio`, `residual_rms`, `noise_bound`, `inlier_extent`,
//! `rotation_uncertainty`, `tilt`, `ambiguity`, `confidence`, `time_ms` (with `suppression`), `read_ms`), the same layout and the same
//! number format: the shortest of `%.15g`, `%.16g` and `%.17g` that reads back to the exact double, `null`
//! for NaN and infinities (and for `information` when refinement did not run). Exit status: 0 valid pose, 1
//! not valid, 2 usage or input error.

use std::fmt::Write as _;
use std::process::ExitCode;
use std::time::Instant;

use kissm::{Config, Format, Matcher, RefineMode, Registration};

const USAGE: &str = "usage: register SRC TGT --voxel V|auto [--threads N] [--json] \
                     [--refine gicp|point-to-plane|none] [--initial T.txt] \
                     [--format FMT | --format-src FMT --format-tgt FMT]\n\
                     FMT: auto, ply, pcd, kitti_bin, bin_xyz, npy, xyz or las";

struct Options {
    files: Vec<String>,
    voxel: Option<f64>,
    threads: usize,
    json: bool,
    source_format: Format,
    target_format: Format,
    /// `--refine`, when given.
    refine: Option<RefineMode>,
    /// `--initial`: refine this transform file's pose instead of registering globally.
    initial: Option<String>,
}

impl Options {
    /// The refinement: `--refine`, else none for a registration and GICP for a refinement (as the tool).
    fn refine_mode(&self) -> RefineMode {
        match (self.refine, &self.initial) {
            (Some(mode), _) => mode,
            (None, Some(_)) => RefineMode::Gicp,
            (None, None) => RefineMode::None,
        }
    }
}

/// The tool's names of the refine modes.
fn refine_name(mode: RefineMode) -> &'static str {
    match mode {
        RefineMode::None => "none",
        RefineMode::Gicp => "gicp",
        RefineMode::PointToPlane => "point-to-plane",
    }
}

fn parse_refine(text: &str) -> Result<RefineMode, String> {
    match text {
        "none" => Ok(RefineMode::None),
        "gicp" => Ok(RefineMode::Gicp),
        "point-to-plane" | "point_to_plane" => Ok(RefineMode::PointToPlane),
        _ => Err(format!("--refine: unknown refinement '{text}' (expected gicp, point-to-plane or none)")),
    }
}

/// Reads a transform file: 4 rows of 4 finite numbers; blank lines and lines starting with `#` ignored.
fn read_transform(path: &str) -> Result<[[f64; 4]; 4], String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("--initial: cannot read '{path}': {e}"))?;
    let mut m = [[0.0; 4]; 4];
    let mut rows = 0;
    for (number, line) in text.lines().enumerate() {
        let tokens: Vec<&str> = line.split_whitespace().collect();
        if tokens.first().map_or(true, |t| t.starts_with('#')) {
            continue;
        }
        let place = format!("--initial: '{path}' line {}", number + 1);
        if rows == 4 {
            return Err(format!("{place}: a transform has 4 rows, this is a fifth"));
        }
        if tokens.len() != 4 {
            return Err(format!("{place} holds {} values; a transform row has 4", tokens.len()));
        }
        for (out, token) in m[rows].iter_mut().zip(&tokens) {
            *out = token
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite())
                .ok_or(format!("{place}: '{token}' is not a finite number"))?;
        }
        rows += 1;
    }
    if rows != 4 {
        return Err(format!("--initial: '{path}' holds {rows} rows; a transform has 4 rows of 4 numbers"));
    }
    Ok(m)
}

fn parse_args() -> Result<Options, String> {
    let mut opt = Options {
        files: Vec::new(),
        voxel: None,
        threads: 0,
        json: false,
        source_format: Format::Auto,
        target_format: Format::Auto,
        refine: None,
        initial: None,
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
                // "auto": 0, the library's suggestion for the pair (reported as voxel_size_used).
                opt.voxel = Some(if text == "auto" {
                    0.0
                } else {
                    text.parse().map_err(|_| format!("--voxel: '{text}' is not a number or auto"))?
                });
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
            "--refine" => opt.refine = Some(parse_refine(&value("--refine")?)?),
            "--initial" => opt.initial = Some(value("--initial")?),
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
    if opt.initial.is_some() && opt.refine == Some(RefineMode::None) {
        return Err("--refine none: refining from --initial needs gicp or point-to-plane".to_string());
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

/// `v` as C's `printf("%.{precision}g", v)` writes it (both round correctly): `precision` significant
/// digits, trailing zeros dropped, scientific notation (`e+XX`) when the exponent is below -4 or at least
/// `precision`. For finite `v`.
fn c_format_g(v: f64, precision: usize) -> String {
    let scientific = format!("{:.*e}", precision - 1, v);
    let (mantissa, exponent) = scientific.split_once('e').unwrap_or((&scientific, "0"));
    let exponent: i32 = exponent.parse().unwrap_or(0);
    let trim = |digits: &str| -> String {
        if digits.contains('.') {
            digits.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            digits.to_string()
        }
    };
    if exponent < -4 || exponent >= precision as i32 {
        let sign = if exponent < 0 { '-' } else { '+' };
        format!("{}e{sign}{:02}", trim(mantissa), exponent.abs())
    } else {
        let decimals = (precision as i32 - 1 - exponent) as usize;
        trim(&format!("{v:.decimals$}"))
    }
}

/// A JSON number as the C tool writes it: the shortest of `%.15g`, `%.16g` and `%.17g` that reads back to
/// exactly `v` (`%.17g` always does); `null` for NaN and infinities.
fn json_number(v: f64) -> String {
    if !v.is_finite() {
        return "null".to_string();
    }
    (15..17)
        .map(|precision| c_format_g(v, precision))
        .find(|text| text.parse::<f64>() == Ok(v))
        .unwrap_or_else(|| c_format_g(v, 17))
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

fn to_json(opt: &Options, reg: &Registration, initial: Option<&[[f64; 4]; 4]>, read_ms: f64) -> String {
    let c = &reg.counts;
    let t = &reg.timings;
    let fine = reg.refinement;
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
        ("refine_correspondences", fine.map_or(0, |f| f.correspondences)),
        ("source_suppressed", c.source_suppressed),
        ("target_suppressed", c.target_suppressed),
    ]
    .map(|(key, value)| (key, value.to_string()));
    let times = [
        ("voxelize", t.voxelize_ms),
        ("features", t.features_ms),
        ("suppression", t.suppression_ms),
        ("matching", t.matching_ms),
        ("pruning", t.pruning_ms),
        ("solver", t.solver_ms),
        ("refine", t.refine_ms),
        ("total", t.total_ms),
    ]
    .map(|(key, value)| (key, json_number(value)));
    let nan = f64::NAN;
    let mut fields = vec![
        ("version", json_string(kissm::version())),
        ("source", json_string(&opt.files[0])),
        ("target", json_string(&opt.files[1])),
        ("voxel_size", json_number(reg.voxel_size_used)),
        ("threads", opt.threads.to_string()),
        ("valid", reg.valid.to_string()),
        ("reason", json_string(reg.reason.as_str())),
        ("reason_code", reg.reason.code().to_string()),
    ];
    if let Some(initial) = initial {
        fields.push(("initial_transform", json_matrix(initial)));
    }
    fields.extend([
        ("transform", json_matrix(&reg.transform)),
        ("rotation", json_matrix(&reg.rotation)),
        ("translation", json_row(&reg.translation)),
        ("coarse_transform", json_matrix(&reg.coarse_transform)),
        ("refine", json_string(refine_name(opt.refine_mode()))),
        ("information", fine.map_or("null".to_string(), |f| json_matrix(&f.information))),
        ("overlap", json_number(fine.map_or(nan, |f| f.overlap))),
        ("refine_rmse", json_number(fine.map_or(nan, |f| f.rmse))),
        ("refine_condition", json_number(fine.map_or(nan, |f| f.condition))),
        ("degenerate", reg.degenerate().to_string()),
        ("weak_directions", json_matrix(reg.weak_directions())),
        ("inlier_coverage", json_number(fine.map_or(nan, |f| f.inlier_coverage))),
        ("refine_iterations", fine.map_or(0, |f| f.iterations).to_string()),
        ("refine_converged", fine.is_some_and(|f| f.converged).to_string()),
        ("final_inliers", reg.final_inliers().to_string()),
        ("voxel_size_used", json_number(reg.voxel_size_used)),
        ("counts", json_object(&counts, 4)),
        ("inlier_ratio", json_number(reg.inlier_ratio)),
        ("residual_rms", json_number(reg.residual_rms)),
        ("noise_bound", json_number(reg.noise_bound)),
        ("inlier_extent", json_row(&reg.inlier_extent)),
        ("rotation_uncertainty", json_number(reg.rotation_uncertainty)),
        ("tilt", json_number(reg.tilt)),
        ("ambiguity", json_number(reg.ambiguity)),
        ("confidence", json_number(reg.confidence)),
        ("time_ms", json_object(&times, 4)),
        ("read_ms", json_number(read_ms)),
    ]);
    json_object(&fields, 2) + "\n"
}

fn print_matrix(m: &[[f64; 4]; 4]) {
    for row in m {
        println!("  [ {:12.6} {:12.6} {:12.6} {:12.6} ]", row[0], row[1], row[2], row[3]);
    }
}

fn print_summary(opt: &Options, reg: &Registration, read_ms: f64) {
    let command = if opt.initial.is_some() { "refine" } else { "register" };
    println!("kissm {} {command} (Rust)", kissm::version());
    println!("  source: {} ({} points)", opt.files[0], reg.counts.source_points);
    println!("  target: {} ({} points)", opt.files[1], reg.counts.target_points);
    println!(
        "  voxel {}{}, threads {}, refinement {}, files read in {:.1} ms",
        reg.voxel_size_used,
        if opt.voxel == Some(0.0) { " (auto)" } else { "" },
        opt.threads,
        refine_name(opt.refine_mode()),
        read_ms
    );
    if let Some(path) = &opt.initial {
        println!("initial transform (from {path}):");
        print_matrix(&reg.coarse_transform);
    }
    println!("{}transform (maps source into target, row-major):", if reg.is_refined() { "refined " } else { "" });
    print_matrix(&reg.transform);
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
    if opt.initial.is_none() {
        println!("rotation uncertainty: {:.4} deg", reg.rotation_uncertainty.to_degrees());
    }
    if let Some(fine) = reg.refinement {
        println!(
            "refinement: {} iterations, {}; {} correspondences; overlap {:.4}, inlier coverage {:.4}, rmse {:.4}, \
             condition {:.4}",
            fine.iterations,
            if fine.converged { "converged" } else { "stopped at the iteration cap" },
            fine.correspondences,
            fine.overlap,
            fine.inlier_coverage,
            fine.rmse,
            fine.condition
        );
        let weak = fine.weak_directions();
        if fine.degenerate {
            let plural = if weak.len() == 1 { "" } else { "s" };
            println!(
                "  degenerate: {} free direction{plural} (rotation [rad], translation [m], source frame)",
                weak.len()
            );
            for v in weak {
                println!("    ({:.3} {:.3} {:.3} | {:.3} {:.3} {:.3})", v[0], v[1], v[2], v[3], v[4], v[5]);
            }
        }
    }
    println!("time: {:.1} ms", reg.timings.total_ms);
}

fn run(opt: &Options, initial: Option<&[[f64; 4]; 4]>) -> Result<Registration, kissm::Error> {
    let config = Config::builder()
        .voxel_size(opt.voxel.unwrap_or(f64::NAN))
        .num_threads(opt.threads)
        .refine_mode(opt.refine_mode())
        .build()?;
    let read_start = Instant::now();
    let source = kissm::read_points_with_format(&opt.files[0], opt.source_format)?;
    let target = kissm::read_points_with_format(&opt.files[1], opt.target_format)?;
    let read_ms = read_start.elapsed().as_secs_f64() * 1e3;
    let mut matcher = Matcher::new(&config)?;
    let reg = match initial {
        Some(initial) => matcher.refine(&source, &target, initial)?,
        None => matcher.register(&source, &target)?,
    };
    if opt.json {
        print!("{}", to_json(opt, &reg, initial, read_ms));
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
    let initial = match opt.initial.as_deref().map(read_transform).transpose() {
        Ok(initial) => initial,
        Err(message) => {
            eprintln!("register: {message}");
            return ExitCode::from(2);
        }
    };
    match run(&opt, initial.as_ref()) {
        Ok(reg) if reg.valid => ExitCode::SUCCESS,
        Ok(_) => ExitCode::from(1),
        Err(e) => {
            eprintln!("register: {e}");
            ExitCode::from(2)
        }
    }
}
