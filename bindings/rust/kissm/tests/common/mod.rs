//! Helpers shared by the integration tests: a deterministic synthetic scene, pose maths, skip messages,
//! the data and CLI locations, and a small JSON reader for the `kissm` tool's output.
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
// Random numbers (splitmix64) and the synthetic scene
// ------------------------------------------------------------------------------------------------

pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1) with 53 random bits.
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
    /// Standard normal (Box-Muller).
    pub fn gauss(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

/// Samples a walled yard (about 24 m x 16 m, ground 1.7 m below the origin) with boxes, poles and a
/// ramp, at about `density` points per square metre with 1 cm noise. Deterministic in `seed`.
pub fn yard(seed: u64, density: f64) -> Vec<[f64; 3]> {
    let mut rng = Rng::new(seed);
    let mut pts = Vec::new();
    let ground = -1.7;
    // An axis-aligned rectangle: origin o, edge vectors u and v.
    let quad = |rng: &mut Rng, pts: &mut Vec<[f64; 3]>, o: [f64; 3], u: [f64; 3], v: [f64; 3]| {
        let cross = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
        let area = (cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]).sqrt();
        let n = (area * density).round() as usize;
        for _ in 0..n {
            let (a, b) = (rng.uniform(), rng.uniform());
            let mut p = [0.0; 3];
            for k in 0..3 {
                p[k] = o[k] + a * u[k] + b * v[k] + 0.01 * rng.gauss();
            }
            pts.push(p);
        }
    };
    // Ground and three walls of different heights.
    quad(&mut rng, &mut pts, [-12.0, -8.0, ground], [24.0, 0.0, 0.0], [0.0, 16.0, 0.0]);
    quad(&mut rng, &mut pts, [-12.0, 8.0, ground], [24.0, 0.0, 0.0], [0.0, 0.0, 4.0]);
    quad(&mut rng, &mut pts, [12.0, -8.0, ground], [0.0, 16.0, 0.0], [0.0, 0.0, 3.0]);
    quad(&mut rng, &mut pts, [-12.0, -8.0, ground], [0.0, 9.0, 0.0], [0.0, 0.0, 2.5]);
    // Boxes: (centre x, centre y, size x, size y, height).
    let boxes = [
        (-6.0, 3.0, 2.0, 1.2, 1.5),
        (4.0, -4.0, 1.0, 3.0, 2.2),
        (7.5, 5.0, 2.5, 2.5, 0.8),
        (-2.0, -5.5, 1.4, 0.8, 1.1),
        (1.0, 4.5, 0.7, 0.7, 2.8),
    ];
    for &(cx, cy, sx, sy, h) in &boxes {
        let (x0, y0) = (cx - sx / 2.0, cy - sy / 2.0);
        quad(&mut rng, &mut pts, [x0, y0, ground], [sx, 0.0, 0.0], [0.0, 0.0, h]);
        quad(&mut rng, &mut pts, [x0, y0 + sy, ground], [sx, 0.0, 0.0], [0.0, 0.0, h]);
        quad(&mut rng, &mut pts, [x0, y0, ground], [0.0, sy, 0.0], [0.0, 0.0, h]);
        quad(&mut rng, &mut pts, [x0 + sx, y0, ground], [0.0, sy, 0.0], [0.0, 0.0, h]);
        quad(&mut rng, &mut pts, [x0, y0, ground + h], [sx, 0.0, 0.0], [0.0, sy, 0.0]);
    }
    // A ramp.
    quad(&mut rng, &mut pts, [-9.0, -6.0, ground], [4.0, 0.0, 1.2], [0.0, 2.5, 0.0]);
    // Poles: (x, y, radius, height).
    for &(x, y, r, h) in
        &[(-3.0, 0.5, 0.15, 3.5), (5.5, 1.0, 0.25, 2.5), (9.0, -6.0, 0.12, 4.0), (-10.0, 6.0, 0.3, 2.0)]
    {
        let n = (2.0 * std::f64::consts::PI * r * h * density).round() as usize;
        for _ in 0..n {
            let a = rng.range(0.0, 2.0 * std::f64::consts::PI);
            let z = rng.range(0.0, h);
            pts.push([
                x + r * a.cos() + 0.01 * rng.gauss(),
                y + r * a.sin() + 0.01 * rng.gauss(),
                ground + z + 0.01 * rng.gauss(),
            ]);
        }
    }
    pts
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

/// The synthetic pair: the yard sampled twice with different seeds, the second copy moved by `truth`
/// (a 130 degree yaw with some tilt and a 6 m shift), so `truth` maps source into target.
pub struct SyntheticPair {
    pub source: Vec<[f64; 3]>,
    pub target: Vec<[f64; 3]>,
    pub truth: Pose,
}

pub fn synthetic_pair() -> &'static SyntheticPair {
    static PAIR: OnceLock<SyntheticPair> = OnceLock::new();
    PAIR.get_or_init(|| {
        let truth = Pose::axis_angle([0.05, -0.03, 1.0], 130.0, [3.5, -4.0, 0.3]);
        let source = yard(1, 30.0);
        let target = yard(2, 30.0).into_iter().map(|p| truth.apply(p)).collect();
        SyntheticPair { source, target, truth }
    })
}

/// The voxel size used with the synthetic pair.
pub const SYNTHETIC_VOXEL: f64 = 0.3;

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
    // The tool writes NaN as null; any NaN matches it.
    let equal = if c.is_nan() { rust.is_nan() } else { c.to_bits() == rust.to_bits() };
    if !equal {
        failures.push(format!("{what}: C {c:?} vs Rust {rust:?}"));
    }
}

/// Every field of `reg` against the tool's `--json` output (all but the timings): the transform,
/// rotation, translation, inlier ratio, residual, noise bound and inlier extent bit for bit, the counts,
/// validity and reason exactly. Returns the differences.
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
    let transform = json.get("transform").arr();
    assert_eq!(transform.len(), 4, "transform rows");
    for (i, row) in transform.iter().enumerate() {
        for (j, v) in row.nums().into_iter().enumerate() {
            same_bits(&format!("transform[{i}][{j}]"), v, reg.transform[i][j], &mut failures);
        }
    }
    for (i, row) in json.get("rotation").arr().iter().enumerate() {
        for (j, v) in row.nums().into_iter().enumerate() {
            same_bits(&format!("rotation[{i}][{j}]"), v, reg.rotation[i][j], &mut failures);
        }
    }
    for (i, v) in json.get("translation").nums().into_iter().enumerate() {
        same_bits(&format!("translation[{i}]"), v, reg.translation[i], &mut failures);
    }
    same_bits("inlier_ratio", json.get("inlier_ratio").num(), reg.inlier_ratio, &mut failures);
    same_bits("residual_rms", json.get("residual_rms").num(), reg.residual_rms, &mut failures);
    same_bits("noise_bound", json.get("noise_bound").num(), reg.noise_bound, &mut failures);
    for (i, v) in json.get("inlier_extent").nums().into_iter().enumerate() {
        same_bits(&format!("inlier_extent[{i}]"), v, reg.inlier_extent[i], &mut failures);
    }
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
