//! Mutation fuzz of the model loaders: the Newell teapot, two OpenSubdiv OBJ files, a
//! glTF and a GLB are mutated (see [`tessera_tests::fuzz`]) and each mutant is loaded
//! and validated as the CLI does before tessellating. Every mutant must either load or
//! fail with one line naming the file: never a panic, a hang or a huge allocation.
//!
//! `TESSERA_FUZZ_MUTANTS` sets the mutants per loader (default 1000), `TESSERA_FUZZ_SEED`
//! the seed; `cargo xtask fuzz N` runs this with N mutants in release mode.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::fmt;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::Arc;
use std::time::{Duration, Instant};

use tessera_core::bezier::{BezierModel, PreparedBezier};
use tessera_core::catmull_clark::{PatchMesh, SurfaceModel, TREE_DEPTH};
use tessera_tests::fuzz::{self, mutant_seed, mutate, Input, Rng};

/// The system allocator, recording each thread's largest request: a count read from a
/// file that sizes an allocation shows up here even when the OS would lazily grant it.
struct Watch;

#[global_allocator]
static WATCH: Watch = Watch;

thread_local! {
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}

/// Requests from this size on are refused (the process aborts, naming the size):
/// granting them could take the machine down before the mutant is reported.
const REFUSED: usize = 1 << 33;

/// The largest single allocation a mutant may ask for; the inputs are a few KiB.
const ALLOWED: usize = 64 << 20;

fn watch(size: usize) -> bool {
    let _ = LARGEST.try_with(|l| l.set(l.get().max(size)));
    if size >= REFUSED {
        use std::io::Write;
        let _ = writeln!(
            std::io::stderr(),
            "loader_fuzz: refused an allocation of {size} bytes (the mutant is the last file written to the fuzz directory)"
        );
        return false;
    }
    true
}

unsafe impl GlobalAlloc for Watch {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if watch(layout.size()) {
            System.alloc(layout)
        } else {
            std::ptr::null_mut()
        }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if watch(layout.size()) {
            System.alloc_zeroed(layout)
        } else {
            std::ptr::null_mut()
        }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if watch(new_size) {
            System.realloc(ptr, layout, new_size)
        } else {
            std::ptr::null_mut()
        }
    }
}

/// Loads one file as far as the CLI goes before tessellating; the error text if it fails.
type Loader = Arc<dyn Fn(&Path) -> Result<(), String> + Send + Sync>;

/// A Newell teaset file: the model and what the tessellators prepare from it.
fn load_newell(path: &Path) -> Result<(), String> {
    let model = BezierModel::load(path).map_err(|e| e.to_string())?;
    let prepared = PreparedBezier::new(&model);
    std::hint::black_box((&prepared, model.bounds()));
    Ok(())
}

/// A Catmull-Clark control mesh (OBJ, glTF or GLB by extension): its first subdivision
/// and patches; on a non-manifold edge, cut there as `--split-non-manifold` does.
fn load_control_mesh(path: &Path) -> Result<(), String> {
    let mut control = tessera_core::io::load_control_mesh(path).map_err(|e| e.to_string())?;
    let mesh = match PatchMesh::new(&control) {
        Ok(mesh) => mesh,
        Err(e) => {
            let e = e.to_string();
            if let Err(why) = check_error(&e, path) {
                panic!("{why}");
            }
            if !e.contains("non-manifold") {
                return Err(e);
            }
            control.split_non_manifold().map_err(|e| e.to_string())?;
            PatchMesh::new(&control).map_err(|e| e.to_string())?
        }
    };
    let model = SurfaceModel::new(mesh, TREE_DEPTH);
    std::hint::black_box((&model, control.bbox_diag()));
    Ok(())
}

/// An error must be one line naming the file, then the problem.
fn check_error(e: &str, file: &Path) -> Result<(), String> {
    let name = file.display().to_string();
    if e.contains('\n') {
        Err(format!("the error is not one line: {e:?}"))
    } else if !e.starts_with(&name) || e.len() <= name.len() + 2 {
        Err(format!(
            "the error does not start with the file name {name:?}: {e:?}"
        ))
    } else {
        Ok(())
    }
}

#[derive(Debug)]
enum Problem {
    Panic(String),
    Hang(Duration),
    Allocation(usize),
    BadError(String),
    /// The fuzzing thread itself stopped (it could not write a mutant).
    Harness(String),
}

#[derive(Debug)]
struct Failure {
    input: &'static str,
    index: usize,
    seed: u64,
    ops: Vec<String>,
    file: PathBuf,
    problem: Problem,
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let what = match &self.problem {
            Problem::Panic(m) => format!("panicked: {m}"),
            Problem::Hang(d) => format!("took more than {d:?}"),
            Problem::Allocation(n) => format!("asked for {n} bytes at once"),
            Problem::BadError(m) => m.clone(),
            Problem::Harness(m) => format!("the fuzzer stopped: {m}"),
        };
        write!(
            f,
            "{} mutant {} (seed {:#018x}, {}): {what}; the mutant is {}",
            self.input,
            self.index,
            self.seed,
            self.ops.join(", "),
            self.file.display()
        )
    }
}

#[derive(Debug, Default)]
struct Summary {
    loaded: usize,
    rejected: usize,
    slowest: Duration,
    largest_allocation: usize,
}

/// A stable id of an input for its mutants' seeds.
fn input_id(name: &str) -> u64 {
    name.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    })
}

/// Mutant `index` (of the input it cycles to) and the file it is written to.
fn nth_mutant(
    inputs: &[Input],
    seed: u64,
    index: usize,
    dir: &Path,
) -> (&'static str, u64, fuzz::Mutant, PathBuf) {
    let input = &inputs[index % inputs.len()];
    let s = mutant_seed(seed, input_id(input.name), index as u64);
    let m = mutate(&mut Rng::new(s), &input.seed);
    let file = dir.join(format!("{}.{}", input.name, input.ext));
    (input.name, s, m, file)
}

enum Outcome {
    Loaded,
    Rejected(String),
    Panicked(String),
}

/// Runs `mutants` mutants of `inputs` (cycling through them) through `load` on another
/// thread, one at a time, each written to a fresh directory. The first mutant that
/// panics, runs longer than `limit`, allocates too much or fails with a malformed
/// error is the failure; the directory is then kept, holding that mutant.
fn run_fuzz(
    inputs: &[Input],
    mutants: usize,
    seed: u64,
    load: Loader,
    limit: Duration,
) -> Result<Summary, Failure> {
    let dir = std::env::temp_dir().join(format!(
        "tessera-fuzz-{}-{}-{seed:x}",
        std::process::id(),
        inputs[0].name
    ));
    std::fs::create_dir_all(&dir).expect("temporary directory");
    let (tx, rx) = mpsc::channel();
    {
        let (inputs, dir) = (inputs.to_vec(), dir.clone());
        std::thread::spawn(move || {
            for index in 0..mutants {
                let (_, _, mutant, file) = nth_mutant(&inputs, seed, index, &dir);
                if let Err(e) = std::fs::write(&file, &mutant.bytes) {
                    let _ = tx.send(Err(format!("{}: {e}", file.display())));
                    return;
                }
                LARGEST.with(|l| l.set(0));
                let t = Instant::now();
                let result = catch_unwind(AssertUnwindSafe(|| load(&file)));
                let (elapsed, largest) = (t.elapsed(), LARGEST.with(Cell::get));
                let outcome = match result {
                    Ok(Ok(())) => Outcome::Loaded,
                    Ok(Err(e)) => Outcome::Rejected(e),
                    Err(payload) => Outcome::Panicked(
                        payload
                            .downcast_ref::<&str>()
                            .map(|s| s.to_string())
                            .or_else(|| payload.downcast_ref::<String>().cloned())
                            .unwrap_or_else(|| "(not a string)".into()),
                    ),
                };
                if tx.send(Ok((outcome, elapsed, largest))).is_err() {
                    return;
                }
            }
        });
    }
    let mut summary = Summary::default();
    for index in 0..mutants {
        let fail = |problem| {
            let (input, seed, mutant, file) = nth_mutant(inputs, seed, index, &dir);
            Failure {
                input,
                index,
                seed,
                ops: mutant.ops,
                file,
                problem,
            }
        };
        let (outcome, elapsed, largest) = match rx.recv_timeout(limit) {
            Ok(Ok(m)) => m,
            Ok(Err(e)) => return Err(fail(Problem::Harness(e))),
            Err(RecvTimeoutError::Timeout) => return Err(fail(Problem::Hang(limit))),
            Err(RecvTimeoutError::Disconnected) => {
                return Err(fail(Problem::Harness("the fuzzing thread died".into())))
            }
        };
        summary.slowest = summary.slowest.max(elapsed);
        summary.largest_allocation = summary.largest_allocation.max(largest);
        if largest > ALLOWED {
            return Err(fail(Problem::Allocation(largest)));
        }
        match outcome {
            Outcome::Loaded => summary.loaded += 1,
            Outcome::Rejected(e) => {
                let (_, _, _, file) = nth_mutant(inputs, seed, index, &dir);
                check_error(&e, &file).map_err(|m| fail(Problem::BadError(m)))?;
                summary.rejected += 1;
            }
            Outcome::Panicked(m) => return Err(fail(Problem::Panic(m))),
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(summary)
}

fn env_number(name: &str, default: u64) -> u64 {
    match std::env::var(name) {
        Ok(v) => {
            let v = v.trim();
            let parsed = match v.strip_prefix("0x") {
                Some(hex) => u64::from_str_radix(hex, 16),
                None => v.parse(),
            };
            parsed.unwrap_or_else(|_| panic!("{name}={v:?} is not a number"))
        }
        Err(_) => default,
    }
}

/// Fuzzes one loader with its inputs; fails on the first bad mutant.
fn fuzz_loader(loader: &str, load: fn(&Path) -> Result<(), String>) {
    let inputs = fuzz::inputs()
        .into_iter()
        .find(|(l, _)| *l == loader)
        .expect("known loader")
        .1;
    // The seeds themselves load: mutants start from valid files.
    let dir = std::env::temp_dir().join(format!(
        "tessera-fuzz-seeds-{}-{loader}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    for input in &inputs {
        let file = dir.join(format!("{}.{}", input.name, input.ext));
        std::fs::write(&file, input.seed.bytes()).unwrap();
        load(&file).unwrap_or_else(|e| panic!("the unmutated {} fails: {e}", input.name));
    }
    let _ = std::fs::remove_dir_all(&dir);
    let mutants = env_number("TESSERA_FUZZ_MUTANTS", 1000) as usize;
    let seed = env_number("TESSERA_FUZZ_SEED", fuzz::DEFAULT_SEED);
    let t = Instant::now();
    let summary = run_fuzz(
        &inputs,
        mutants,
        seed,
        Arc::new(load),
        Duration::from_secs(10),
    )
    .unwrap_or_else(|f| panic!("{f}"));
    eprintln!(
        "{loader}: {mutants} mutants (seed {seed:#x}) in {:.2?}: {} loaded, {} rejected; slowest {:.2?}, largest allocation {} bytes",
        t.elapsed(),
        summary.loaded,
        summary.rejected,
        summary.slowest,
        summary.largest_allocation
    );
    // The mutations reach past the first checks (some mutants still load) and do break
    // files (most do not).
    if mutants >= 100 {
        assert!(
            summary.loaded >= mutants / 50 && summary.rejected >= mutants / 5,
            "{loader}: {summary:?}"
        );
    }
}

#[test]
fn newell_teaset_mutants() {
    fuzz_loader("newell", load_newell);
}

#[test]
fn obj_mutants() {
    fuzz_loader("obj", load_control_mesh);
}

#[test]
fn gltf_mutants() {
    fuzz_loader("gltf", load_control_mesh);
}

#[test]
fn glb_mutants() {
    fuzz_loader("glb", load_control_mesh);
}

/// The harness itself: a loader that panics, hangs, allocates hugely or returns a bad
/// error on one mutant is reported with that mutant's index and seed.
#[test]
fn the_harness_reports_panics_hangs_allocations_and_bad_errors() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let inputs = vec![fuzz::teapot()];
    let on_call = |n: usize, bad: fn(&Path) -> Result<(), String>| -> Loader {
        let calls = AtomicUsize::new(0);
        Arc::new(move |p: &Path| {
            if calls.fetch_add(1, Ordering::SeqCst) == n {
                bad(p)
            } else {
                Err(format!("{}: fine", p.display()))
            }
        })
    };
    let limit = Duration::from_millis(500);
    let fail = |load| run_fuzz(&inputs, 20, 7, load, limit).expect_err("must fail");

    let f = fail(on_call(4, |_| panic!("deliberate")));
    assert!(
        matches!(&f.problem, Problem::Panic(m) if m == "deliberate"),
        "{f}"
    );
    assert_eq!(f.index, 4);
    let expected_seed = mutant_seed(7, input_id("teapot"), 4);
    assert_eq!(f.seed, expected_seed);
    let report = f.to_string();
    assert!(
        report.starts_with("teapot mutant 4 (seed ")
            && report.contains(&format!("{expected_seed:#018x}")),
        "{report}"
    );
    assert!(f.file.exists(), "the mutant is kept: {report}");

    let f = fail(on_call(2, |_| {
        std::thread::sleep(Duration::from_secs(2));
        Ok(())
    }));
    assert!(matches!(f.problem, Problem::Hang(_)) && f.index == 2, "{f}");

    let f = fail(on_call(3, |_| {
        std::hint::black_box(Vec::<u8>::with_capacity(ALLOWED + 1));
        Ok(())
    }));
    assert!(
        matches!(f.problem, Problem::Allocation(_)) && f.index == 3,
        "{f}"
    );

    let f = fail(on_call(5, |p| Err(format!("{}: two\nlines", p.display()))));
    assert!(
        matches!(f.problem, Problem::BadError(_)) && f.index == 5,
        "{f}"
    );
    let f = fail(on_call(6, |_| Err("no file name".into())));
    assert!(
        matches!(f.problem, Problem::BadError(_)) && f.index == 6,
        "{f}"
    );

    // A loader that behaves passes, and every mutant is counted.
    let s = run_fuzz(&inputs, 20, 7, on_call(usize::MAX, |_| Ok(())), limit).unwrap();
    assert_eq!((s.loaded, s.rejected), (0, 20));
}
