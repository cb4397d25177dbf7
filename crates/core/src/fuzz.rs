//! Seeded mutation fuzzing for the robustness tests: a deterministic generator, structured
//! JSON and byte-level mutators, and a harness that runs each input under `catch_unwind`,
//! counts panics with where they happened, and writes the first panicking input out.
//!
//! The tests of the glTF loader (`lightlab-scene`), the bake-folder readers (`lightlab-bake`)
//! and the image readers (here) use it with fixed seeds, so every run tries the same inputs;
//! `LIGHTLAB_FUZZ_SEED` and `LIGHTLAB_FUZZ_ROUNDS` explore further by hand. Written here rather
//! than with cargo-fuzz, which needs a nightly compiler and is not deterministic per run.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A small deterministic generator (SplitMix64).
pub struct Rng(pub u64);
impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
}

/// Values that break arithmetic: zero, signs, powers of two around integer widths, huge floats.
const INTERESTING: &[f64] = &[
    0.0,
    -1.0,
    1.0,
    3.0,
    4.0,
    255.0,
    256.0,
    65535.0,
    65536.0,
    2147483647.0,
    4294967295.0,
    4294967296.0,
    1e19,
    -1e19,
    1e39,
    1e300,
    0.5,
    1e-45,
];

/// Change one number, key or array somewhere in a JSON document.
pub fn mutate_json(v: &mut serde_json::Value, rng: &mut Rng) {
    use serde_json::Value;
    let mut node = v;
    loop {
        let children = match node {
            Value::Object(m) => m.len(),
            Value::Array(a) => a.len(),
            _ => 0,
        };
        if children == 0 || rng.below(4) == 0 {
            break;
        }
        let k = rng.below(children);
        node = match node {
            Value::Object(m) => m.values_mut().nth(k).unwrap(),
            Value::Array(a) => &mut a[k],
            _ => unreachable!(),
        };
    }
    match (rng.below(6), &mut *node) {
        (0 | 1, n) => *n = serde_json::json!(INTERESTING[rng.below(INTERESTING.len())]),
        (2, Value::Object(m)) if !m.is_empty() => {
            let key = m.keys().nth(rng.below(m.len())).unwrap().clone();
            m.remove(&key);
        }
        (3, Value::Array(a)) if !a.is_empty() => {
            let x = a[rng.below(a.len())].clone();
            a.push(x);
        }
        (4, Value::String(s)) => {
            *s = ["../x.bin", "%FF", "data:,", "data:;base64,@@", "/", ""][rng.below(6)].into()
        }
        (_, n) => *n = serde_json::json!(rng.below(8) as i64 - 2),
    }
}

pub fn mutate_bytes(b: &mut Vec<u8>, rng: &mut Rng) {
    let n = b.len().max(1);
    match rng.below(5) {
        0 => {
            let i = rng.below(n);
            if let Some(x) = b.get_mut(i) {
                *x ^= 1 << rng.below(8);
            }
        }
        1 => {
            let i = rng.below(n);
            if let Some(x) = b.get_mut(i) {
                *x = [0, 0xff, 0x7f, 0x80, b'"', b'[', b'9'][rng.below(7)];
            }
        }
        2 => b.truncate(rng.below(n)),
        3 => {
            let (i, j) = (rng.below(n), rng.below(n));
            let len = b.len();
            b.drain(i.min(j).min(len)..i.max(j).min(len));
        }
        _ => {
            let i = rng.below(n).min(b.len());
            let chunk: Vec<u8> = b[i..(i + 16).min(b.len())].to_vec();
            b.splice(i..i, chunk);
        }
    }
}

/// Runs inputs under `catch_unwind`, counting panics (see the module documentation).
pub struct Fuzzer {
    pub rng: Rng,
    pub rounds: u64,
    inputs: usize,
    accepted: usize,
    panics: Vec<String>,
    start: std::time::Instant,
    thread: Option<String>,
}

/// Where the last silenced panic happened, per fuzzing thread (set by the panic hook).
static WHERE: Mutex<Vec<(String, String)>> = Mutex::new(Vec::new());
/// How many fuzzers are running (their threads' panics are silenced while they run).
static RUNNING: AtomicUsize = AtomicUsize::new(0);
static HOOK: std::sync::Once = std::sync::Once::new();

fn fuzzing_threads() -> std::sync::MutexGuard<'static, Vec<(String, String)>> {
    WHERE.lock().unwrap_or_else(|p| p.into_inner())
}

impl Fuzzer {
    /// `rounds` and `seed` unless LIGHTLAB_FUZZ_ROUNDS / LIGHTLAB_FUZZ_SEED say otherwise.
    pub fn from_env(rounds: u64, seed: u64) -> Self {
        let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<u64>().ok());
        HOOK.call_once(|| {
            let previous = std::panic::take_hook();
            std::panic::set_hook(Box::new(move |info| {
                let name = std::thread::current().name().map(String::from);
                let mut threads = fuzzing_threads();
                match threads.iter_mut().find(|(t, _)| Some(t) == name.as_ref()) {
                    Some((_, at)) if RUNNING.load(Ordering::SeqCst) > 0 => {
                        *at = info
                            .location()
                            .map(|l| format!("{}:{}", l.file(), l.line()))
                            .unwrap_or_default();
                    }
                    _ => {
                        drop(threads);
                        previous(info)
                    }
                }
            }));
        });
        let thread = std::thread::current().name().map(String::from);
        if let Some(t) = &thread {
            fuzzing_threads().push((t.clone(), String::new()));
        }
        RUNNING.fetch_add(1, Ordering::SeqCst);
        Fuzzer {
            rng: Rng(env("LIGHTLAB_FUZZ_SEED").unwrap_or(seed)),
            rounds: env("LIGHTLAB_FUZZ_ROUNDS").unwrap_or(rounds),
            inputs: 0,
            accepted: 0,
            panics: vec![],
            start: std::time::Instant::now(),
            thread,
        }
    }

    /// `bytes` with one to three byte-level mutations.
    pub fn mutated_bytes(&mut self, bytes: &[u8]) -> Vec<u8> {
        let mut b = bytes.to_vec();
        for _ in 0..=self.rng.below(3) {
            mutate_bytes(&mut b, &mut self.rng);
        }
        b
    }

    /// `bytes` parsed as JSON with one to three structured mutations; None if not JSON.
    pub fn mutated_json(&mut self, bytes: &[u8]) -> Option<Vec<u8>> {
        let mut v: serde_json::Value = serde_json::from_slice(bytes).ok()?;
        for _ in 0..=self.rng.below(3) {
            mutate_json(&mut v, &mut self.rng);
        }
        serde_json::to_vec(&v).ok()
    }

    /// Run one input; `f` returns whether it was accepted. A panic is recorded with `label`,
    /// its message and location, and the first panicking input is written to the temporary
    /// folder.
    pub fn run(&mut self, label: &str, input: &[u8], f: impl FnOnce() -> bool) {
        self.inputs += 1;
        match catch_unwind(AssertUnwindSafe(f)) {
            Ok(ok) => self.accepted += ok as usize,
            Err(p) => {
                let msg = p
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                let at = fuzzing_threads()
                    .iter()
                    .find(|(t, _)| Some(t) == self.thread.as_ref())
                    .map(|(_, at)| at.clone())
                    .unwrap_or_default();
                if self.panics.is_empty() {
                    let _ = std::fs::write(std::env::temp_dir().join("lightlab-fuzz-panic"), input);
                }
                self.panics.push(format!("{label}: {msg} at {at}"));
            }
        }
    }

    /// Print the figures and fail if any input panicked or fewer than `min_inputs` ran.
    pub fn finish(self, what: &str, min_inputs: usize) {
        RUNNING.fetch_sub(1, Ordering::SeqCst);
        eprintln!(
            "{what} fuzz: {} inputs, {} accepted, {} panics, {:.1} s",
            self.inputs,
            self.accepted,
            self.panics.len(),
            self.start.elapsed().as_secs_f64()
        );
        assert!(self.inputs >= min_inputs, "only {} inputs ran", self.inputs);
        assert!(
            self.panics.is_empty(),
            "{what}: {} of {} inputs panicked (the first is in {}):\n{}",
            self.panics.len(),
            self.inputs,
            std::env::temp_dir().join("lightlab-fuzz-panic").display(),
            self.panics[..self.panics.len().min(10)].join("\n")
        );
    }
}
