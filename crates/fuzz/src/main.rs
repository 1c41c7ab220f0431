//! `cell_fuzz`: runs the fuzz targets on mutated inputs and prints, per target, the inputs run,
//! inputs per second and findings.
//!
//! ```text
//! cargo run -p cell_fuzz --release -- --inputs 1000000            # every target
//! cargo run -p cell_fuzz --release -- --target stl --inputs 100000 --seed 7
//! cargo run -p cell_fuzz --release -- --list
//! ```
//!
//! With no `--target`, each target runs in its own child process (this binary again), so a
//! target that aborts (an allocation over the cap) or hangs ends only its own run. A finding's
//! input is saved as `crates/fuzz/corpus/<target>/<sha256>`, and `cargo test -p cell_fuzz`
//! replays it from then on.

use std::alloc::{GlobalAlloc, Layout, System};
use std::process::{Command, ExitCode, Stdio};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Duration;

use clap::Parser;

use cell_fuzz::run::{self, Options, Report};

/// The memory guard: one allocation over `SINGLE_CAP`, or more than `LIVE_CAP` bytes live, is a
/// finding (`run::oversized_allocation` saves the input and aborts).
struct Guard;

static SINGLE_CAP: AtomicUsize = AtomicUsize::new(1 << 30);
static LIVE_CAP: AtomicUsize = AtomicUsize::new(2 << 30);
static LIVE: AtomicUsize = AtomicUsize::new(0);
static TRIPPED: AtomicBool = AtomicBool::new(false);

fn check(size: usize) {
    let over = size > SINGLE_CAP.load(Ordering::Relaxed)
        || LIVE.load(Ordering::Relaxed).saturating_add(size) > LIVE_CAP.load(Ordering::Relaxed);
    // Once tripped, the report's own small allocations go through.
    if over && !TRIPPED.swap(true, Ordering::SeqCst) {
        run::oversized_allocation(size);
    }
}

// SAFETY: every call is forwarded to `System` with the same layout; the counters only observe.
unsafe impl GlobalAlloc for Guard {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        check(layout.size());
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            LIVE.fetch_add(layout.size(), Ordering::Relaxed);
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        check(layout.size());
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            LIVE.fetch_add(layout.size(), Ordering::Relaxed);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        check(new_size.saturating_sub(layout.size()));
        if new_size > SINGLE_CAP.load(Ordering::Relaxed) {
            check(new_size);
        }
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
            LIVE.fetch_add(new_size, Ordering::Relaxed);
        }
        p
    }
}

#[global_allocator]
static GLOBAL: Guard = Guard;

#[derive(Parser, Debug)]
#[command(about = "Fuzz cellsuite's parsers on stable Rust")]
struct Args {
    /// Run only these targets (repeat the flag); all when absent.
    #[arg(long)]
    target: Vec<String>,
    /// Inputs per target.
    #[arg(long, default_value_t = 100_000)]
    inputs: u64,
    /// Seed of the mutator.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Longest time one input may take, seconds (longer is a hang).
    #[arg(long, default_value_t = 10.0)]
    timeout_s: f64,
    /// Largest single allocation, MiB (larger is a finding).
    #[arg(long, default_value_t = 1024)]
    max_alloc_mib: usize,
    /// Do not save findings under crates/fuzz/corpus.
    #[arg(long)]
    no_save: bool,
    /// Child processes running targets at once.
    #[arg(long, default_value_t = 1)]
    jobs: usize,
    /// List the targets and exit.
    #[arg(long)]
    list: bool,
    /// Run these input files once through the one `--target` and say how each went.
    #[arg(long, num_args = 1..)]
    replay: Vec<std::path::PathBuf>,
    /// Run the one given target in this process (what the parent starts).
    #[arg(long, hide = true)]
    child: bool,
}

fn main() -> ExitCode {
    let args = Args::parse();
    SINGLE_CAP.store(args.max_alloc_mib << 20, Ordering::Relaxed);
    LIVE_CAP.store((args.max_alloc_mib << 21).max(2 << 30), Ordering::Relaxed);
    let all = cell_fuzz::targets();
    if args.list {
        for t in &all {
            println!("{:<22} {}", t.name, t.about);
        }
        return ExitCode::SUCCESS;
    }
    let names: Vec<String> = if args.target.is_empty() {
        all.iter().map(|t| t.name.to_string()).collect()
    } else {
        args.target.clone()
    };
    if let Some(bad) = names.iter().find(|n| cell_fuzz::target(n).is_none()) {
        eprintln!("no target {bad:?}; --list names them");
        return ExitCode::from(2);
    }
    if !args.replay.is_empty() {
        return replay(&args, &names[0]);
    }
    if args.child {
        return child(&args, &names[0]);
    }
    parent(&args, &names)
}

fn options(args: &Args) -> Options {
    Options {
        inputs: args.inputs,
        seed: args.seed,
        timeout: Duration::from_secs_f64(args.timeout_s),
        save: !args.no_save,
    }
}

/// Runs one target here and prints its result line; exits at once (a hung worker thread
/// must not keep the process alive).
fn child(args: &Args, name: &str) -> ExitCode {
    let target = cell_fuzz::target(name).expect("checked");
    let report = run::run(&target, &options(args));
    for f in &report.findings {
        eprintln!(
            "FINDING {name}: {:?} ×{} {} (saved: {})",
            f.kind,
            f.hits,
            f.message,
            f.saved
                .as_ref()
                .map_or("no".into(), |p| p.display().to_string())
        );
    }
    let line = serde_json::json!({
        "target": report.target,
        "inputs": report.inputs,
        "seconds": report.elapsed.as_secs_f64(),
        "findings": report.findings.len(),
        "crashing_inputs": report.findings.iter().map(|f| f.hits).sum::<u64>(),
        "hang": report.hung(),
    });
    println!("RESULT {line}");
    use std::io::Write as _;
    let _ = std::io::stdout().flush();
    let _ = std::io::stderr().flush();
    std::process::exit(i32::from(!report.findings.is_empty()))
}

/// Runs each file once through `name`: prints the outcome and the time taken (a hang is
/// reported after `--timeout-s`, and the process exits).
fn replay(args: &Args, name: &str) -> ExitCode {
    let target = cell_fuzz::target(name).expect("checked");
    let mut failed = false;
    for path in &args.replay {
        let Ok(input) = std::fs::read(path) else {
            eprintln!("{}: cannot read", path.display());
            return ExitCode::from(2);
        };
        let (tx, rx) = std::sync::mpsc::channel();
        let started = std::time::Instant::now();
        std::thread::spawn(move || {
            let _ = tx.send(run::run_one(&target, &input));
        });
        match rx.recv_timeout(Duration::from_secs_f64(args.timeout_s)) {
            Ok(Ok(())) => println!("{}: ok in {:?}", path.display(), started.elapsed()),
            Ok(Err(panic)) => {
                failed = true;
                println!("{}: PANIC {panic}", path.display());
            }
            Err(_) => {
                println!(
                    "{}: HANG (no return after {:?})",
                    path.display(),
                    started.elapsed()
                );
                std::process::exit(1);
            }
        }
    }
    if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}

/// One child's outcome, as the table shows it.
struct Row {
    name: String,
    inputs: u64,
    per_second: f64,
    findings: u64,
    note: String,
}

fn parent(args: &Args, names: &[String]) -> ExitCode {
    let exe = std::env::current_exe().expect("own path");
    println!(
        "{:<22} {:>10} {:>10} {:>9}  note",
        "target", "inputs", "inputs/s", "findings"
    );
    let mut rows = Vec::new();
    for batch in names.chunks(args.jobs.max(1)) {
        let children: Vec<_> = batch
            .iter()
            .map(|name| {
                let mut c = Command::new(&exe);
                c.args(["--child", "--target", name])
                    .args(["--inputs", &args.inputs.to_string()])
                    .args(["--seed", &args.seed.to_string()])
                    .args(["--timeout-s", &args.timeout_s.to_string()])
                    .args(["--max-alloc-mib", &args.max_alloc_mib.to_string()])
                    .stdout(Stdio::piped())
                    .stderr(Stdio::inherit());
                if args.no_save {
                    c.arg("--no-save");
                }
                (name.clone(), c.spawn().expect("start a child"))
            })
            .collect();
        for (name, child) in children {
            let pid = child.id();
            let out = child.wait_with_output().expect("child output");
            remove_scratch_of(pid);
            let row = row_of(&name, &out);
            println!(
                "{:<22} {:>10} {:>10.0} {:>9}  {}",
                row.name, row.inputs, row.per_second, row.findings, row.note
            );
            rows.push(row);
        }
    }
    let total: u64 = rows.iter().map(|r| r.findings).sum();
    println!(
        "{} targets, {} inputs, {total} findings",
        rows.len(),
        rows.iter().map(|r| r.inputs).sum::<u64>()
    );
    if total == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}

/// Removes the scratch directories a child left (one that aborted or hung cannot).
fn remove_scratch_of(pid: u32) {
    let prefix = format!("cell_fuzz-{pid}-");
    for base in [std::path::PathBuf::from("/dev/shm"), std::env::temp_dir()] {
        for e in std::fs::read_dir(&base).into_iter().flatten().flatten() {
            if e.file_name().to_string_lossy().starts_with(&prefix) {
                let _ = std::fs::remove_dir_all(e.path());
            }
        }
    }
}

fn row_of(name: &str, out: &std::process::Output) -> Row {
    let text = String::from_utf8_lossy(&out.stdout);
    let result = text
        .lines()
        .find_map(|l| l.strip_prefix("RESULT "))
        .and_then(|j| serde_json::from_str::<serde_json::Value>(j).ok());
    match result {
        Some(v) => {
            let inputs = v["inputs"].as_u64().unwrap_or(0);
            let seconds = v["seconds"].as_f64().unwrap_or(0.0);
            let report = Report {
                target: "",
                inputs,
                elapsed: Duration::from_secs_f64(seconds),
                findings: Vec::new(),
            };
            Row {
                name: name.into(),
                inputs,
                per_second: report.per_second(),
                findings: v["findings"].as_u64().unwrap_or(0),
                note: if v["hang"].as_bool() == Some(true) {
                    "stopped on a hang".into()
                } else if v["aborted"].as_bool() == Some(true) {
                    format!("stopped on an oversized allocation ({})", out.status)
                } else {
                    String::new()
                },
            }
        }
        None => Row {
            name: name.into(),
            inputs: 0,
            per_second: 0.0,
            findings: 1,
            note: format!("child ended without a result ({})", out.status),
        },
    }
}
