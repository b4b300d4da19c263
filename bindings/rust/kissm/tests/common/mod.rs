// SPDX-License-Identifier: MIT
//! Helpers shared by the integration tests: the shared test scene (the committed pair of `tests/data`)
//! and variations of it, pose maths, skip messages, the data and CLI locations, and a small JSON reader
//! for the `kissm` tool's output.
#![allow(dead_code, clippy::needless_range_loop)]

use std::io::Write as _;
use std::path::PathBuf;
use std::sync::OnceLock;

/// Prints a SKIP line that cargo's output capture does not swallow.
pub fn skip(test: &str, why: &str) {
    let _ = writeln!(std::io::stderr(), "SKIP {test}: {why}");
}

/// `KISSM_DATA_DIR`, else `../shared/data` beside the repository; `None` when absent.
pub fn data_dir() -> Option<PathBuf> {
    let dir = match std::env::var_os("KISSM_DATA_DIR") {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../../shared/data"),
    };
    dir.is_dir().then_some(dir)
}

/// The `kissm` tool: `KISSM_CLI`, else `KISSM_BUILD_DIR/kissm`, else the repository's `build/kissm`.
pub fn cli() -> Option<PathBuf> {
    let candidates = [
        std::env::var_os("KISSM_CLI").map(PathBuf::from),
        std::env::var_os("KISSM_BUILD_DIR").map(|d| PathBuf::from(d).join("kissm")),
        Some(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../build/kissm")),
    ];
    candidates.into_iter().flatten().find(|p| p.is_file())
}

/// A fresh, empty temporary folder for one test.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("kissm-rs-{}-{}", name, std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create a temporary folder");
    dir
}

// ------------------------------------------------------------------------------------------------
// Poses
// ------------------------------------------------------------------------------------------------

#[derive(Clone, Copy, Debug)]
pub struct Pose {
    pub r: [[f64; 3]; 3],
    pub t: [f64; 3],
}

impl Pose {
    pub fn axis_angle(axis: [f64; 3], angle_deg: f64, t: [f64; 3]) -> Pose {
        let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
        let (x, y, z) = (axis[0] / n, axis[1] / n, axis[2] / n);
        let a = angle_deg.to_radians();
        let (c, s) = (a.cos(), a.sin());
        let k = 1.0 - c;
        Pose {
            r: [
                [c + x * x * k, x * y * k - z * s, x * z * k + y * s],
                [y * x * k + z * s, c + y * y * k, y * z * k - x * s],
                [z * x * k - y * s, z * y * k + x * s, c + z * z * k],
            ],
            t,
        }
    }

    pub fn from_matrix(m: &[[f64; 4]; 4]) -> Pose {
        let mut r = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                r[i][j] = m[i][j];
            }
        }
        Pose { r, t: [m[0][3], m[1][3], m[2][3]] }
    }

    /// The 4 x 4 homogeneous matrix, `[row][col]`.
    pub fn to_matrix(self) -> [[f64; 4]; 4] {
        let mut m = [[0.0, 0.0, 0.0, 1.0]; 4];
        for i in 0..3 {
            m[i][..3].copy_from_slice(&self.r[i]);
            m[i][3] = self.t[i];
        }
        m
    }

    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        let r = &self.r;
        [
            r[0][0] * p[0] + r[0][1] * p[1] + r[0][2] * p[2] + self.t[0],
            r[1][0] * p[0] + r[1][1] * p[1] + r[1][2] * p[2] + self.t[1],
            r[2][0] * p[0] + r[2][1] * p[1] + r[2][2] * p[2] + self.t[2],
        ]
    }

    /// self * other (apply other first).
    pub fn compose(&self, other: &Pose) -> Pose {
        let mut r = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                r[i][j] = (0..3).map(|k| self.r[i][k] * other.r[k][j]).sum();
            }
        }
        Pose { r, t: self.apply(other.t) }
    }

    pub fn inverse(&self) -> Pose {
        let mut r = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                r[i][j] = self.r[j][i];
            }
        }
        let t = [
            -(r[0][0] * self.t[0] + r[0][1] * self.t[1] + r[0][2] * self.t[2]),
            -(r[1][0] * self.t[0] + r[1][1] * self.t[1] + r[1][2] * self.t[2]),
            -(r[2][0] * self.t[0] + r[2][1] * self.t[1] + r[2][2] * self.t[2]),
        ];
        Pose { r, t }
    }

    /// Rotation error (degrees) and translation error (units) of `estimate` against `self` (the truth).
    pub fn errors(&self, estimate: &Pose) -> (f64, f64) {
        let trace: f64 = (0..3).map(|i| (0..3).map(|k| self.r[k][i] * estimate.r[k][i]).sum::<f64>()).sum();
        let cos = ((trace - 1.0) / 2.0).clamp(-1.0, 1.0);
        let dt = [estimate.t[0] - self.t[0], estimate.t[1] - self.t[1], estimate.t[2] - self.t[2]];
        (cos.acos().to_degrees(), (dt[0] * dt[0] + dt[1] * dt[1] + dt[2] * dt[2]).sqrt())
    }
}

/// Whether two matrices hold the same bits in every element.
pub fn same_bits_matrix<const R: usize, const C: usize>(a: &[[f64; C]; R], b: &[[f64; C]; R]) -> bool {
    a.iter().flatten().zip(b.iter().flatten()).all(|(x, y)| x.to_bits() == y.to_bits())
}

// ------------------------------------------------------------------------------------------------
// The shared test scene: the committed pair of tests/data (the C and Python suites read the same files)
// ------------------------------------------------------------------------------------------------

/// The folder with the committed test data (`roundtrip_source.ply`, `roundtrip_target.ply`,
/// `roundtrip_ground_truth.txt`, `golden.json`): `KISSM_TEST_DATA`, else the repository's `tests/data`;
/// `None` when it does not hold the pair.
pub fn test_data_dir() -> Option<PathBuf> {
    let dir = match std::env::var_os("KISSM_TEST_DATA") {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../tests/data"),
    };
    dir.join("roundtrip_source.ply").is_file().then_some(dir)
}

/// Whether missing test data is a failure instead of a skip (`KISSM_REQUIRE_TEST_DATA=1`, set by
/// run_tests.sh and package_test.sh so that those runs cannot pass by skipping).
pub fn test_data_required() -> bool {
    std::env::var_os("KISSM_REQUIRE_TEST_DATA").is_some_and(|v| v == "1")
}

/// The shared scene: source, target and the ground-truth pose that maps source into target.
pub struct Scene {
    pub source: Vec<[f64; 3]>,
    pub target: Vec<[f64; 3]>,
    pub truth: Pose,
}

/// The voxel size the scene is registered with (that of the golden file's float64 case).
pub const SCENE_VOXEL: f64 = 0.25;

/// Reads `roundtrip_ground_truth.txt`: `#` comment lines, then four rows of four numbers.
pub fn read_ground_truth(path: &std::path::Path) -> Pose {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("read {}: {e}", path.display()));
    let values: Vec<f64> = text
        .lines()
        .filter(|l| !l.trim_start().starts_with('#'))
        .flat_map(str::split_whitespace)
        .map(|v| v.parse().unwrap_or_else(|e| panic!("{}: {v:?}: {e}", path.display())))
        .collect();
    assert_eq!(values.len(), 16, "{}: 16 numbers expected", path.display());
    assert_eq!(&values[12..], &[0.0, 0.0, 0.0, 1.0], "{}: last row", path.display());
    let mut m = [[0.0; 4]; 4];
    for (i, v) in values.into_iter().enumerate() {
        m[i / 4][i % 4] = v;
    }
    Pose::from_matrix(&m)
}

/// The shared scene, read once per test binary. `None` (after a SKIP line naming `test`) when the data is
/// absent, unless [`test_data_required`], which panics instead.
pub fn scene(test: &str) -> Option<&'static Scene> {
    static SCENE: OnceLock<Option<Scene>> = OnceLock::new();
    let scene = SCENE.get_or_init(|| {
        let dir = test_data_dir()?;
        let read =
            |name: &str| kissm::read_points(dir.join(name)).unwrap_or_else(|e| panic!("read {name}: {e}")).to_vec();
        Some(Scene {
            source: read("roundtrip_source.ply"),
            target: read("roundtrip_target.ply"),
            truth: read_ground_truth(&dir.join("roundtrip_ground_truth.txt")),
        })
    });
    if scene.is_none() {
        let why = "the test scene was not found (tests/data of the repository, or set KISSM_TEST_DATA)";
        assert!(!test_data_required(), "{test}: {why}, and KISSM_REQUIRE_TEST_DATA=1");
        skip(test, why);
    }
    scene.as_ref()
}

/// A prior such as odometry gives: `truth` turned by 3 degrees about a tilted axis and moved by about 0.3
/// (a little over a voxel of the shared scene).
pub fn perturbed(truth: &Pose) -> Pose {
    Pose::axis_angle([0.2, -0.3, 1.0], 3.0, [0.2, -0.15, 0.17]).compose(truth)
}

/// A flat, featureless plane z = 0: a 71 x 71 grid 0.14 apart, nudged within the plane by a fixed formula
/// so that it is not a perfect lattice.
pub fn flat_plane() -> Vec<[f64; 3]> {
    (0..71 * 71)
        .map(|i| {
            let (x, y) = ((i % 71) as f64, (i / 71) as f64);
            [-5.0 + 0.14 * x + 0.03 * (1.7 * y).sin(), -5.0 + 0.14 * y + 0.03 * (2.3 * x).cos(), 0.0]
        })
        .collect()
}

/// `points` moved by `pose`.
pub fn moved(points: &[[f64; 3]], pose: &Pose) -> Vec<[f64; 3]> {
    points.iter().map(|&p| pose.apply(p)).collect()
}

/// `points` reordered by a fixed formula: element `i` is `points[(i * step + offset) % n]` with `step`
/// the first number from about 0.618 n up that is coprime to n, so every point appears exactly once.
pub fn permuted(points: &[[f64; 3]], offset: usize) -> Vec<[f64; 3]> {
    let n = points.len();
    let gcd = |mut a: usize, mut b: usize| {
        while b != 0 {
            (a, b) = (b, a % b);
        }
        a
    };
    let step = (n * 618 / 1000..).find(|&s| s > 0 && gcd(s, n) == 1).expect("a coprime step");
    (0..n).map(|i| points[(i * step + offset) % n]).collect()
}

/// `copies` copies of `points`, copy `k` shifted by `k * spacing` along x: a larger cloud of the same
/// surfaces (for calls that must run long enough to be cancelled).
pub fn tiled(points: &[[f64; 3]], copies: usize, spacing: f64) -> Vec<[f64; 3]> {
    (0..copies).flat_map(|k| points.iter().map(move |p| [p[0] + k as f64 * spacing, p[1], p[2]])).collect()
}

// ------------------------------------------------------------------------------------------------
// A small JSON reader (enough for the kissm tool's output; numbers parse to the exact doubles)
// ------------------------------------------------------------------------------------------------

#[derive(Clone, Debug, PartialEq)]
pub enum Json {
    Null,
    Bool(bool),
    Num(f64),
    Str(String),
    Arr(Vec<Json>),
    Obj(Vec<(String, Json)>),
}

impl Json {
    pub fn parse(text: &str) -> Result<Json, String> {
        let mut p = Parser { s: text.as_bytes(), i: 0 };
        let v = p.value()?;
        p.ws();
        if p.i != p.s.len() {
            return Err(format!("trailing text at byte {}", p.i));
        }
        Ok(v)
    }

    pub fn get(&self, key: &str) -> &Json {
        static NULL: Json = Json::Null;
        match self {
            Json::Obj(fields) => fields.iter().find(|(k, _)| k == key).map(|(_, v)| v).unwrap_or(&NULL),
            _ => &NULL,
        }
    }

    pub fn has(&self, key: &str) -> bool {
        matches!(self, Json::Obj(fields) if fields.iter().any(|(k, _)| k == key))
    }

    /// A number (`null` reads as NaN, like the tool writes NaN).
    pub fn num(&self) -> f64 {
        match self {
            Json::Num(v) => *v,
            Json::Null => f64::NAN,
            other => panic!("expected a number, got {other:?}"),
        }
    }

    pub fn u64(&self) -> u64 {
        let v = self.num();
        assert!(v >= 0.0 && v.fract() == 0.0, "expected a count, got {v}");
        v as u64
    }

    pub fn bool(&self) -> bool {
        match self {
            Json::Bool(b) => *b,
            other => panic!("expected a boolean, got {other:?}"),
        }
    }

    pub fn str(&self) -> &str {
        match self {
            Json::Str(s) => s,
            other => panic!("expected a string, got {other:?}"),
        }
    }

    pub fn arr(&self) -> &[Json] {
        match self {
            Json::Arr(items) => items,
            other => panic!("expected an array, got {other:?}"),
        }
    }

    pub fn nums(&self) -> Vec<f64> {
        self.arr().iter().map(Json::num).collect()
    }
}

struct Parser<'a> {
    s: &'a [u8],
    i: usize,
}

impl Parser<'_> {
    fn ws(&mut self) {
        while self.i < self.s.len() && self.s[self.i].is_ascii_whitespace() {
            self.i += 1;
        }
    }

    fn eat(&mut self, c: u8) -> Result<(), String> {
        self.ws();
        if self.s.get(self.i) == Some(&c) {
            self.i += 1;
            Ok(())
        } else {
            Err(format!("expected '{}' at byte {}", c as char, self.i))
        }
    }

    fn literal(&mut self, word: &str, v: Json) -> Result<Json, String> {
        if self.s[self.i..].starts_with(word.as_bytes()) {
            self.i += word.len();
            Ok(v)
        } else {
            Err(format!("bad literal at byte {}", self.i))
        }
    }

    fn value(&mut self) -> Result<Json, String> {
        self.ws();
        match self.s.get(self.i).copied() {
            Some(b'{') => {
                self.i += 1;
                let mut fields = Vec::new();
                self.ws();
                if self.s.get(self.i) == Some(&b'}') {
                    self.i += 1;
                    return Ok(Json::Obj(fields));
                }
                loop {
                    self.ws();
                    let key = self.string()?;
                    self.eat(b':')?;
                    fields.push((key, self.value()?));
                    self.ws();
                    match self.s.get(self.i) {
                        Some(b',') => self.i += 1,
                        Some(b'}') => {
                            self.i += 1;
                            return Ok(Json::Obj(fields));
                        }
                        _ => return Err(format!("expected ',' or '}}' at byte {}", self.i)),
                    }
                }
            }
            Some(b'[') => {
                self.i += 1;
                let mut items = Vec::new();
                self.ws();
                if self.s.get(self.i) == Some(&b']') {
                    self.i += 1;
                    return Ok(Json::Arr(items));
                }
                loop {
                    items.push(self.value()?);
                    self.ws();
                    match self.s.get(self.i) {
                        Some(b',') => self.i += 1,
                        Some(b']') => {
                            self.i += 1;
                            return Ok(Json::Arr(items));
                        }
                        _ => return Err(format!("expected ',' or ']' at byte {}", self.i)),
                    }
                }
            }
            Some(b'"') => Ok(Json::Str(self.string()?)),
            Some(b't') => self.literal("true", Json::Bool(true)),
            Some(b'f') => self.literal("false", Json::Bool(false)),
            Some(b'n') => self.literal("null", Json::Null),
            Some(_) => {
                let start = self.i;
                while self.i < self.s.len() && matches!(self.s[self.i], b'0'..=b'9' | b'-' | b'+' | b'.' | b'e' | b'E')
                {
                    self.i += 1;
                }
                let text = std::str::from_utf8(&self.s[start..self.i]).map_err(|e| e.to_string())?;
                text.parse::<f64>().map(Json::Num).map_err(|_| format!("bad number '{text}' at byte {start}"))
            }
            None => Err("unexpected end of input".to_string()),
        }
    }

    fn string(&mut self) -> Result<String, String> {
        self.eat(b'"')?;
        let mut out = Vec::new();
        loop {
            let c = *self.s.get(self.i).ok_or("unterminated string")?;
            self.i += 1;
            match c {
                b'"' => break,
                b'\\' => {
                    let e = *self.s.get(self.i).ok_or("unterminated escape")?;
                    self.i += 1;
                    match e {
                        b'n' => out.push(b'\n'),
                        b't' => out.push(b'\t'),
                        b'r' => out.push(b'\r'),
                        b'b' => out.push(8),
                        b'f' => out.push(12),
                        b'u' => {
                            let hex = std::str::from_utf8(self.s.get(self.i..self.i + 4).ok_or("short \\u escape")?)
                                .map_err(|e| e.to_string())?;
                            let code = u32::from_str_radix(hex, 16).map_err(|e| e.to_string())?;
                            self.i += 4;
                            let ch = char::from_u32(code).unwrap_or('\u{fffd}');
                            out.extend_from_slice(ch.to_string().as_bytes());
                        }
                        other => out.push(other),
                    }
                }
                other => out.push(other),
            }
        }
        String::from_utf8(out).map_err(|e| e.to_string())
    }
}

// ------------------------------------------------------------------------------------------------
// Comparing a Rust registration with the C tool's JSON, bit for bit
// ------------------------------------------------------------------------------------------------

fn same_bits(what: &str, c: f64, rust: f64, failures: &mut Vec<String>) {
    // The tool writes NaN and infinities as null (read as NaN here); any of them matches it.
    let equal = if c.is_nan() { !rust.is_finite() } else { c.to_bits() == rust.to_bits() };
    if !equal {
        failures.push(format!("{what}: C {c:?} vs Rust {rust:?}"));
    }
}

/// A 4 x 4 (or any) nested JSON matrix against Rust rows, bit for bit.
fn same_matrix<const C: usize>(what: &str, json: &Json, rows: &[[f64; C]], failures: &mut Vec<String>) {
    let json_rows = json.arr();
    if json_rows.len() != rows.len() {
        failures.push(format!("{what}: C has {} rows, Rust {}", json_rows.len(), rows.len()));
        return;
    }
    for (i, (row, rust)) in json_rows.iter().zip(rows).enumerate() {
        let values = row.nums();
        if values.len() != C {
            failures.push(format!("{what}[{i}]: C has {} columns, Rust {C}", values.len()));
            continue;
        }
        for (j, v) in values.into_iter().enumerate() {
            same_bits(&format!("{what}[{i}][{j}]"), v, rust[j], failures);
        }
    }
}

/// The refinement keys of the tool's `--json` output against `reg`: `coarse_transform`, `information`
/// (`null` exactly when refinement did not run), `overlap`, `refine_rmse`, `refine_condition`,
/// `inlier_coverage` bit for bit (null == NaN), `refine_iterations`, `refine_converged` and `counts.refine_correspondences` exactly.
fn compare_refinement_with_cli_json(json: &Json, reg: &kissm::Registration, failures: &mut Vec<String>) {
    same_matrix("coarse_transform", json.get("coarse_transform"), &reg.coarse_transform, failures);
    let fine = reg.refinement;
    match (json.get("information"), &fine) {
        (Json::Null, None) => {}
        (info @ Json::Arr(_), Some(f)) => same_matrix("information", info, &f.information, failures),
        (info, _) => failures.push(format!("information: C {info:?} vs Rust refinement {:?}", fine.is_some())),
    }
    let nan = f64::NAN;
    same_bits("overlap", json.get("overlap").num(), fine.map_or(nan, |f| f.overlap), failures);
    same_bits("refine_rmse", json.get("refine_rmse").num(), fine.map_or(nan, |f| f.rmse), failures);
    same_bits("refine_condition", json.get("refine_condition").num(), fine.map_or(nan, |f| f.condition), failures);
    same_bits("inlier_coverage", json.get("inlier_coverage").num(), fine.map_or(nan, |f| f.inlier_coverage), failures);
    let iterations = fine.map_or(0, |f| u64::from(f.iterations));
    if json.get("refine_iterations").u64() != iterations {
        failures.push(format!("refine_iterations: C {} vs Rust {iterations}", json.get("refine_iterations").u64()));
    }
    let converged = fine.is_some_and(|f| f.converged);
    if json.get("refine_converged").bool() != converged {
        failures.push(format!("refine_converged: C {} vs Rust {converged}", json.get("refine_converged").bool()));
    }
    let correspondences = fine.map_or(0, |f| f.correspondences);
    if json.get("counts").get("refine_correspondences").u64() != correspondences {
        failures.push(format!(
            "counts.refine_correspondences: C {} vs Rust {correspondences}",
            json.get("counts").get("refine_correspondences").u64()
        ));
    }
}

/// Every field of `reg` against the tool's `--json` output (all but the timings): the transform,
/// rotation, translation, inlier ratio, residual, noise bound, inlier extent and rotation uncertainty bit for
/// bit (null == NaN or infinite), the counts,
/// validity and reason exactly, and the refinement keys (`compare_refinement_with_cli_json`). Returns the
/// differences.
pub fn compare_with_cli_json(json: &Json, reg: &kissm::Registration) -> Vec<String> {
    let mut failures = Vec::new();
    if json.get("valid").bool() != reg.valid {
        failures.push(format!("valid: C {} vs Rust {}", json.get("valid").bool(), reg.valid));
    }
    if json.get("reason_code").num() as i32 != reg.reason.code() {
        failures.push(format!("reason_code: C {} vs Rust {}", json.get("reason_code").num(), reg.reason.code()));
    }
    if json.get("reason").str() != reg.reason.as_str() {
        failures.push(format!("reason: C {} vs Rust {}", json.get("reason").str(), reg.reason.as_str()));
    }
    same_matrix("transform", json.get("transform"), &reg.transform, &mut failures);
    same_matrix("rotation", json.get("rotation"), &reg.rotation, &mut failures);
    for (i, v) in json.get("translation").nums().into_iter().enumerate() {
        same_bits(&format!("translation[{i}]"), v, reg.translation[i], &mut failures);
    }
    same_bits("inlier_ratio", json.get("inlier_ratio").num(), reg.inlier_ratio, &mut failures);
    same_bits("residual_rms", json.get("residual_rms").num(), reg.residual_rms, &mut failures);
    same_bits("noise_bound", json.get("noise_bound").num(), reg.noise_bound, &mut failures);
    for (i, v) in json.get("inlier_extent").nums().into_iter().enumerate() {
        same_bits(&format!("inlier_extent[{i}]"), v, reg.inlier_extent[i], &mut failures);
    }
    same_bits("rotation_uncertainty", json.get("rotation_uncertainty").num(), reg.rotation_uncertainty, &mut failures);
    let c = &reg.counts;
    let counts = json.get("counts");
    let pairs = [
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
    ];
    for (key, rust) in pairs {
        let cv = counts.get(key).u64();
        if cv != rust {
            failures.push(format!("counts.{key}: C {cv} vs Rust {rust}"));
        }
    }
    if json.get("final_inliers").u64() != reg.final_inliers() {
        failures.push(format!("final_inliers: C {} vs Rust {}", json.get("final_inliers").u64(), reg.final_inliers()));
    }
    compare_refinement_with_cli_json(json, reg, &mut failures);
    failures
}

/// Runs the tool with `args` and parses its stdout as JSON (exit 0 or 1 both mean it ran).
pub fn run_cli_json(cli: &std::path::Path, args: &[&std::ffi::OsStr]) -> Json {
    let out = std::process::Command::new(cli).args(args).output().expect("run the kissm tool");
    let code = out.status.code().unwrap_or(-1);
    assert!(
        code == 0 || code == 1,
        "{} {:?} exited with {code}: {}",
        cli.display(),
        args,
        String::from_utf8_lossy(&out.stderr)
    );
    Json::parse(&String::from_utf8_lossy(&out.stdout)).expect("the tool's --json output parses")
}

/// Compiles only when `T` is `Send`.
pub fn assert_send<T: Send>() {}
/// Compiles only when `T` is `Sync`.
pub fn assert_sync<T: Sync>() {}

/// `<T as NotSync<_>>::check()` resolves only when `T` is not `Sync` (otherwise the call is ambiguous and fails
/// to compile).
pub trait NotSync<A> {
    fn check() {}
}
impl<T: ?Sized> NotSync<()> for T {}
impl<T: ?Sized + Sync> NotSync<u8> for T {}

/// Runs `work` while another thread calls `cancel` over and over (a request made before a call starts is
/// dropped, so one request could miss it), and returns what `work` returned.
pub fn while_cancelling<T>(cancel: impl Fn() + Send + 'static, work: impl FnOnce() -> T) -> T {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;
    let done = Arc::new(AtomicBool::new(false));
    let spammer = {
        let done = Arc::clone(&done);
        std::thread::spawn(move || {
            while !done.load(Ordering::Relaxed) {
                cancel();
                std::thread::yield_now();
            }
        })
    };
    let outcome = work();
    done.store(true, Ordering::Relaxed);
    spammer.join().unwrap();
    outcome
}
