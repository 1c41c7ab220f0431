//! The driver: runs a target on mutated inputs and catches what goes wrong.
//!
//! - A **panic** is caught (`catch_unwind`) and recorded with its message and place; the run
//!   goes on. Inputs that panic at the same place count as one finding.
//! - A **hang**: a watchdog (the calling thread) checks that each input returns within
//!   [`Options::timeout`]; one that does not is a finding, and the run of that target stops
//!   (the hung thread cannot be stopped from outside; the driver binary exits after its report).
//! - A **huge allocation**: the driver binary's counting allocator calls
//!   [`oversized_allocation`], which saves the input and ends the process (an allocation that
//!   cannot be refused is an abort, so this is the last thing the process does).
//!
//! Each finding's input is saved as `corpus/<target>/<sha256 of the input>` unless the run is a
//! dry one.

use std::collections::BTreeMap;
use std::io::Write as _;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, Once};
use std::time::{Duration, Instant};

use sha2::{Digest, Sha256};

use crate::mutate::Mutator;
use crate::Target;

/// How a run goes.
#[derive(Debug, Clone)]
pub struct Options {
    /// Inputs to run (seeds and corpus entries first, then mutations).
    pub inputs: u64,
    /// Seed of the mutator's random numbers.
    pub seed: u64,
    /// Longest time one input may take.
    pub timeout: Duration,
    /// Save each finding's input under `corpus/<target>/`.
    pub save: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            inputs: 10_000,
            seed: 1,
            timeout: Duration::from_secs(10),
            save: true,
        }
    }
}

/// What went wrong with one input.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Kind {
    /// The target panicked.
    Panic,
    /// The target did not return within the timeout.
    Hang,
}

/// One distinct finding: the first input that showed it.
#[derive(Debug, Clone)]
pub struct Finding {
    /// Panic or hang.
    pub kind: Kind,
    /// The panic's message and place (`file:line`), or the hang's duration.
    pub message: String,
    /// The input.
    pub input: Vec<u8>,
    /// Inputs that hit the same place.
    pub hits: u64,
    /// Where the input was saved.
    pub saved: Option<PathBuf>,
}

/// The outcome of a run of one target.
#[derive(Debug, Clone)]
pub struct Report {
    /// The target's name.
    pub target: &'static str,
    /// Inputs run.
    pub inputs: u64,
    /// Wall time.
    pub elapsed: Duration,
    /// Distinct findings.
    pub findings: Vec<Finding>,
}

impl Report {
    /// Inputs per second.
    pub fn per_second(&self) -> f64 {
        self.inputs as f64 / self.elapsed.as_secs_f64().max(1e-9)
    }

    /// Whether the run stopped on a hang.
    pub fn hung(&self) -> bool {
        self.findings.iter().any(|f| f.kind == Kind::Hang)
    }
}

/// The input being run, shared with the watchdog and the allocation guard.
struct Current {
    target: &'static str,
    input: Vec<u8>,
    save: bool,
}

/// Input in flight: the watchdog reads the start time, the allocation guard the input.
struct Shared {
    current: Mutex<Current>,
    /// Nanoseconds since `base` when the input started; 0 when idle.
    started_ns: AtomicU64,
    base: Instant,
    done: AtomicBool,
    /// Inputs run so far.
    count: AtomicU64,
}

/// The run the allocation guard reports against (the driver binary runs one at a time).
static ACTIVE: Mutex<Option<Arc<Shared>>> = Mutex::new(None);

thread_local! {
    /// Set while this thread runs fuzz inputs: panics are recorded, not printed.
    static FUZZING: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    static LAST_PANIC: std::cell::RefCell<Option<String>> = const { std::cell::RefCell::new(None) };
}

/// Installs (once) a panic hook that records a fuzzing thread's panic instead of printing it
/// and passes every other thread's panic to the previous hook.
fn install_panic_hook() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if FUZZING.with(std::cell::Cell::get) {
                let message = info
                    .payload()
                    .downcast_ref::<&str>()
                    .map(|s| (*s).to_string())
                    .or_else(|| info.payload().downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "(non-string panic)".into());
                let place = info
                    .location()
                    .map(|l| format!("{}:{}", l.file(), l.line()))
                    .unwrap_or_default();
                LAST_PANIC.with(|p| *p.borrow_mut() = Some(format!("{place}: {message}")));
            } else {
                previous(info);
            }
        }));
    });
}

/// Runs `input` through `target` on this thread; `Err` holds the panic's place and message.
pub fn run_one(target: &Target, input: &[u8]) -> Result<(), String> {
    install_panic_hook();
    FUZZING.with(|f| f.set(true));
    let outcome = catch_unwind(AssertUnwindSafe(|| (target.run)(input)));
    FUZZING.with(|f| f.set(false));
    outcome.map_err(|_| {
        LAST_PANIC
            .with(|p| p.borrow_mut().take())
            .unwrap_or_else(|| "(panic)".into())
    })
}

/// Saves a finding's input as `corpus/<target>/<sha256>`; returns the path.
pub fn save_finding(target: &str, input: &[u8]) -> std::io::Result<PathBuf> {
    let dir = crate::corpus_dir(target);
    std::fs::create_dir_all(&dir)?;
    let name: String = Sha256::digest(input)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    let path = dir.join(name);
    std::fs::write(&path, input)?;
    Ok(path)
}

/// The saved findings of `target` (file name and bytes), sorted by name.
pub fn saved_findings(target: &str) -> Vec<(String, Vec<u8>)> {
    let Ok(entries) = std::fs::read_dir(crate::corpus_dir(target)) else {
        return Vec::new();
    };
    let mut out: Vec<(String, Vec<u8>)> = entries
        .filter_map(|e| e.ok())
        .filter(|e| e.path().is_file())
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            std::fs::read(e.path()).ok().map(|b| (name, b))
        })
        .collect();
    out.sort();
    out
}

/// Called by the driver binary's allocator when one allocation asks for more than its cap:
/// saves the input in flight as a finding, says so on stderr and aborts the process.
pub fn oversized_allocation(bytes: usize) -> ! {
    let active = ACTIVE.try_lock().ok().and_then(|a| a.clone());
    if active.is_none() {
        let _ = writeln!(
            std::io::stderr(),
            "FINDING: allocation of {bytes} bytes (over the cap) at\n{}",
            std::backtrace::Backtrace::force_capture()
        );
    }
    if let Some(shared) = active {
        if let Ok(c) = shared.current.try_lock() {
            let saved = if c.save {
                save_finding(c.target, &c.input)
                    .map(|p| p.display().to_string())
                    .unwrap_or_default()
            } else {
                String::new()
            };
            let _ = writeln!(
                std::io::stderr(),
                "FINDING {}: allocation of {bytes} bytes (over the cap); input saved to {saved}",
                c.target
            );
            // The driver's result line, so the parent knows how far the run got.
            let _ = writeln!(
                std::io::stdout(),
                "RESULT {{\"target\":\"{}\",\"inputs\":{},\"seconds\":{},\"findings\":1,\"aborted\":true}}",
                c.target,
                shared.count.load(Ordering::Acquire),
                shared.base.elapsed().as_secs_f64()
            );
            let _ = std::io::stdout().flush();
        }
    }
    std::process::abort()
}

/// Runs `target` for `options.inputs` inputs: every seed and saved finding once, then
/// mutations of them.
pub fn run(target: &Target, options: &Options) -> Report {
    let shared = Arc::new(Shared {
        current: Mutex::new(Current {
            target: target.name,
            input: Vec::new(),
            save: options.save,
        }),
        started_ns: AtomicU64::new(0),
        base: Instant::now(),
        done: AtomicBool::new(false),
        count: AtomicU64::new(0),
    });
    *ACTIVE.lock().unwrap_or_else(|e| e.into_inner()) = Some(shared.clone());
    let findings: Arc<Mutex<BTreeMap<String, Finding>>> = Arc::default();
    let count = Arc::new(AtomicU64::new(0));
    let start = Instant::now();

    let worker = {
        let (shared, findings, count) = (shared.clone(), findings.clone(), count.clone());
        let (target, options) = (*target, options.clone());
        std::thread::Builder::new()
            .name(format!("fuzz-{}", target.name))
            .stack_size(64 << 20)
            .spawn(move || work(&target, &options, &shared, &findings, &count))
            .expect("spawn the fuzz worker")
    };

    // The watchdog.
    let mut hang = None;
    while !shared.done.load(Ordering::Acquire) {
        std::thread::sleep(Duration::from_millis(20));
        let started = shared.started_ns.load(Ordering::Acquire);
        if started == 0 {
            continue;
        }
        let running = shared
            .base
            .elapsed()
            .saturating_sub(Duration::from_nanos(started));
        if running > options.timeout {
            let input = shared
                .current
                .lock()
                .map(|c| c.input.clone())
                .unwrap_or_default();
            hang = Some((running, input));
            break;
        }
    }
    let elapsed = start.elapsed();
    if hang.is_none() {
        let _ = worker.join();
    }
    *ACTIVE.lock().unwrap_or_else(|e| e.into_inner()) = None;
    let mut findings: Vec<Finding> = findings
        .lock()
        .map(|f| f.values().cloned().collect())
        .unwrap_or_default();
    if let Some((running, input)) = hang {
        let saved = options
            .save
            .then(|| save_finding(target.name, &input).ok())
            .flatten();
        findings.push(Finding {
            kind: Kind::Hang,
            message: format!("no return after {running:?}"),
            input,
            hits: 1,
            saved,
        });
    }
    Report {
        target: target.name,
        inputs: count.load(Ordering::Acquire),
        elapsed,
        findings,
    }
}

fn work(
    target: &Target,
    options: &Options,
    shared: &Shared,
    findings: &Mutex<BTreeMap<String, Finding>>,
    count: &AtomicU64,
) {
    let mut corpus: Vec<Vec<u8>> = (target.seeds)();
    corpus.extend(saved_findings(target.name).into_iter().map(|(_, b)| b));
    if corpus.is_empty() {
        corpus.push(Vec::new());
    }
    let mut mutator = Mutator::new(options.seed, target.tokens, target.max_len);
    for i in 0..options.inputs {
        let input = if (i as usize) < corpus.len() {
            corpus[i as usize].clone()
        } else if mutator.below(64) == 0 {
            // Now and then from nothing: tokens and bytes only.
            mutator.mutate(&[], &[])
        } else {
            let a = mutator.below(corpus.len());
            let b = mutator.below(corpus.len());
            mutator.mutate(&corpus[a], &corpus[b])
        };
        if let Ok(mut c) = shared.current.lock() {
            c.input.clear();
            c.input.extend_from_slice(&input);
        }
        let now = shared.base.elapsed().as_nanos() as u64;
        shared.started_ns.store(now.max(1), Ordering::Release);
        let outcome = run_one(target, &input);
        shared.started_ns.store(0, Ordering::Release);
        count.fetch_add(1, Ordering::AcqRel);
        shared.count.fetch_add(1, Ordering::AcqRel);
        if let Err(message) = outcome {
            let place = message.split(": ").next().unwrap_or_default().to_string();
            let mut f = findings.lock().unwrap_or_else(|e| e.into_inner());
            match f.get_mut(&place) {
                Some(known) => {
                    known.hits += 1;
                    // Keep the shortest input for each place.
                    if input.len() < known.input.len() {
                        // The longer one goes, unless it was a saved case already.
                        if let Some(old) = known.saved.take() {
                            if !corpus.contains(&known.input) {
                                let _ = std::fs::remove_file(old);
                            }
                        }
                        known.input = input.clone();
                        known.saved = options
                            .save
                            .then(|| save_finding(target.name, &input).ok())
                            .flatten();
                    }
                }
                None => {
                    let saved = options
                        .save
                        .then(|| save_finding(target.name, &input).ok())
                        .flatten();
                    f.insert(
                        place,
                        Finding {
                            kind: Kind::Panic,
                            message,
                            input: input.clone(),
                            hits: 1,
                            saved,
                        },
                    );
                }
            }
        }
    }
    crate::remove_scratch();
    shared.done.store(true, Ordering::Release);
}
