//! The render controller: progressive rendering on a worker thread, for the workbench window.
//!
//! A [`Controller`] owns a named worker thread (`raylab-progressive`) and its own rayon pool
//! (`raylab-render-N`). [`Controller::submit`] hands it a [`RenderSettings`] and a scene; each
//! submission gets a new *generation*. The worker renders, for the newest generation only:
//!
//! 1. a coarse preview at about 1/8 of the resolution (on screen a frame or two after a change),
//! 2. the full resolution at sample 0 (the pixel centres: the lab's image),
//! 3. further jittered passes, averaged in a [`Film`], up to `samples_per_pixel` (the target),
//!
//! and publishes a [`Frame`] after each pass, at most one every [`MIN_FRAME_INTERVAL`] after the
//! first full-resolution one, growing to one every [`MAX_FRAME_INTERVAL`] as the job goes on
//! ([`frame_interval`]; the last always). Then it sleeps on its channel (no CPU) until the
//! next submission.
//!
//! A submission makes the running pass stale: the pass's `cancelled` closure compares its
//! generation with the current one, so it stops within one row. Publishing checks the generation
//! under the same lock that `submit` bumps it under, so a stale frame is never published after a
//! newer submission, and frames come out in increasing generation order. The UI polls
//! [`Controller::take_frame`], which never waits; a notify callback (the app's
//! `request_repaint`) tells it when there is something to take.
//!
//! The [`Display`] (exposure and curve) is not part of a job: the film stays linear, and each
//! frame is converted to 8 bits with the display in force when it is published
//! ([`Controller::set_display`]). A change never restarts accumulation or re-traces: a running
//! job notices it at its next pass boundary and publishes then, whatever the frame interval; an
//! idle worker is woken and publishes its last frame again (same generation, samples and linear
//! image), converted anew.
//!
//! A job that panics (a bug in the tracer) does not take the worker down: rayon re-raises a
//! panic from its pool on the thread that installed the work, the worker catches it there, reports
//! it through [`Controller::take_error`] with the message and the job's settings, publishes
//! nothing more of that job, and waits for the next one.
//!
//! Nothing here knows about egui. The same settings always give the same image.

use std::any::Any;
use std::panic::AssertUnwindSafe;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, Sender, TryRecvError};
use std::sync::{Arc, Condvar, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::shapes::scene::Scene;
use crate::transport::denoise::quality::estimated_error;
use crate::transport::denoise::{Denoiser, Features, Noisy, denoising_film};
use crate::transport::display::Display;
use crate::transport::film::{Film, Image, NoiseEstimate};
use crate::transport::render::{Cancelled, accumulate_pass, camera_sees_nothing, render_pass};
use crate::transport::settings::{RenderSettings, SettingsError};
use crate::transport::view::{Legend, View, render_view, variance_view};

/// The display a frame's pixels are made with: the one in force, but the lab's for a debug
/// view (one with a legend), whose colours must be its legend's.
fn shown_with(display: Display, legend: Option<&Legend>) -> Display {
    if legend.is_some() {
        Display::default()
    } else {
        display
    }
}

/// The preview's size divisor: a 1024² image previews at 128².
pub const PREVIEW_DIVISOR: u32 = 8;

/// The shortest time between two accumulated frames shown (after the first): 25 a second, as
/// smooth as the eye needs, while passes of a few milliseconds keep accumulating in between.
pub const MIN_FRAME_INTERVAL: Duration = Duration::from_millis(40);

/// The longest time between two accumulated frames shown: 4 a second, once a job has
/// accumulated for a few seconds.
pub const MAX_FRAME_INTERVAL: Duration = Duration::from_millis(250);

/// The time between two accumulated frames shown, `accumulating` after the first full pass
/// began: a tenth of that time, from [`MIN_FRAME_INTERVAL`] up to [`MAX_FRAME_INTERVAL`]. The
/// image on screen is never more than about a tenth of the render's time behind, and a long
/// render is not slowed by its own progress: each frame shown costs the worker a mean, its
/// display pixels and a noise estimate, and the UI a repaint, which on a small machine (and
/// under a software renderer) are taken from the render threads.
pub fn frame_interval(accumulating: Duration) -> Duration {
    (accumulating / 10).clamp(MIN_FRAME_INTERVAL, MAX_FRAME_INTERVAL)
}

/// Images narrower and shorter than this skip the preview: their first full pass is as quick.
pub const PREVIEW_MIN_SIDE: u32 = 64;

/// A finished pass of the newest job.
#[derive(Clone, Debug)]
pub struct Frame {
    /// The submission this frame belongs to (increases with every submission).
    pub generation: u64,
    /// The settings that made it (for a preview, still the full-resolution settings).
    pub settings: RenderSettings,
    /// The image in linear floats: the preview, or the mean of `samples` full passes. Never
    /// denoised: the unbiased estimate.
    pub image: Arc<Image>,
    /// The denoised image ([`crate::transport::denoise`]), when the denoiser is on and the image is noisy
    /// ([`RenderSettings::is_stochastic`]): made from the mean of `denoised_samples` passes,
    /// which may be fewer than `samples` (the worker denoises again only when a tenth of its
    /// time allows).
    pub denoised: Option<Arc<Image>>,
    pub denoised_samples: u32,
    /// The denoised image's estimated error, relative as [`NoiseEstimate::relative_rms_error`]
    /// is ([`crate::transport::denoise::quality::estimated_error`]; `None` for one sample, whose spread
    /// is unknown).
    pub denoised_error: Option<f64>,
    /// How long the last denoising took, in milliseconds (the feature buffers, traced once a
    /// view, not counted).
    pub denoise_ms: f64,
    /// Whether the denoiser was on when the frame was converted (as `display` says which
    /// display was in force).
    pub denoise: bool,
    /// `denoised` if there is one and the denoiser is on, else `image`, through `display`, as
    /// 8-bit RGBA.
    pub rgba: Vec<u8>,
    /// The display `rgba` was converted with (the one in force when the frame was published).
    pub display: Display,
    /// Full-resolution passes averaged so far (0 for a preview).
    pub samples: u32,
    /// The sample target, `settings.samples_per_pixel`.
    pub target: u32,
    /// Whether this is the coarse preview.
    pub is_preview: bool,
    /// Time spent tracing this pass, in milliseconds (a frame published again for a new display
    /// keeps its pass's figures: nothing was traced).
    pub pass_ms: f64,
    /// Primary rays per second of this pass, in millions.
    pub mrays_per_s: f64,
    /// Time from the submission to the end of this pass, in milliseconds.
    pub since_submit_ms: f64,
    /// The estimated remaining noise of the accumulated image (from 2 samples on).
    pub noise: Option<NoiseEstimate>,
    /// For a debug view (`settings.view`), what its colours mean; its pixels are shown with the
    /// lab's display whatever the display in force, so they match the legend.
    pub legend: Option<Legend>,
    /// Why the image is black, when the camera sees nothing at all
    /// ([`crate::transport::render::camera_sees_nothing`], asked here, off the UI thread, once a job).
    pub camera_note: Option<String>,
}

impl Frame {
    /// Whether the sample target is reached: no more passes will come for this generation (a
    /// display change may still publish the frame again, converted anew).
    pub fn is_final(&self) -> bool {
        !self.is_preview && self.samples >= self.target
    }
}

/// Why a submission was refused.
#[derive(Debug, thiserror::Error)]
pub enum ControllerError {
    #[error(transparent)]
    Invalid(#[from] SettingsError),
    #[error("the render thread has stopped")]
    Stopped,
    #[error("could not start the render threads: {0}")]
    Spawn(String),
}

/// Called by the worker after it publishes a frame or meets a problem (the app passes
/// `ctx.request_repaint`).
pub type Notify = Box<dyn Fn() + Send + Sync>;

/// A problem the worker met, for the status line ([`Controller::take_error`]).
#[derive(Clone, Debug, PartialEq)]
pub struct WorkerError {
    /// What happened, in one line: for a job that panicked, the panic's message and the job's
    /// settings in brief ([`RenderSettings::summary`]).
    pub message: String,
    /// The settings of the job that panicked, in full, so the failure can be reproduced
    /// (`raylab render --settings` reads them back as JSON).
    pub settings: Option<RenderSettings>,
}

impl std::fmt::Display for WorkerError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl WorkerError {
    /// The failed job's settings as pretty JSON (a settings file), if there was a job.
    pub fn settings_json(&self) -> Option<String> {
        let settings = self.settings.as_ref()?;
        serde_json::to_string_pretty(settings).ok()
    }
}

/// The message of a panic caught by [`std::panic::catch_unwind`]: `panic!`'s formatted text
/// (a `String` or a `&str`); any other payload is named as such.
pub fn panic_message(payload: &(dyn Any + Send)) -> String {
    if let Some(text) = payload.downcast_ref::<&str>() {
        (*text).to_owned()
    } else if let Some(text) = payload.downcast_ref::<String>() {
        text.clone()
    } else {
        "a panic with no message".to_owned()
    }
}

/// Runs `f`, returning the message of a panic inside it instead of unwinding further.
///
/// For the threads of the workbench (the render worker, the scene loader, the A/B difference):
/// each runs one piece of work whose panic must become a message on the status line, not a
/// thread gone silent. `AssertUnwindSafe` is sound there because nothing `f` may leave half
/// updated is used after a panic: the callers drop the work's results and state, and every
/// lock they share is taken with `unwrap_or_else(PoisonError::into_inner)` on data that stays
/// whole (a frame slot, a number). The default panic hook still prints the message and
/// location on stderr.
pub fn catch_panic<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    std::panic::catch_unwind(AssertUnwindSafe(f)).map_err(|payload| panic_message(&*payload))
}

/// The message of the panic [`Controller::inject_panic_on_next_pass`] causes.
#[doc(hidden)]
pub const INJECTED_PANIC: &str = "injected panic (Controller::inject_panic_on_next_pass)";

enum Message {
    Job {
        generation: u64,
        settings: Box<RenderSettings>,
        scene: Arc<Scene>,
        submitted: Instant,
    },
    Threads {
        generation: u64,
        threads: usize,
    },
    /// The display changed: if idle, publish the last frame again with it.
    Display,
    Quit,
}

/// State shared by the controller and its worker.
struct Shared {
    /// Bumped by every submission and thread change, under `slot`'s lock.
    generation: AtomicU64,
    /// The newest published frame, until the UI takes it.
    slot: Mutex<Option<Frame>>,
    /// Test hook: the worker waits for the frame in `slot` to be taken before it puts the
    /// next one there ([`Controller::keep_every_frame`]); `taken` wakes it.
    keep_every_frame: AtomicBool,
    taken: Condvar,
    /// The newest generation the worker has finished (target reached), for [`Controller::wait_idle`].
    done: Mutex<u64>,
    done_changed: Condvar,
    /// Jobs abandoned before their target because a newer submission arrived.
    abandoned_jobs: AtomicU64,
    /// A problem the worker met (the thread pool could not be rebuilt, a job panicked), until
    /// the UI takes it.
    error: Mutex<Option<WorkerError>>,
    /// The display frames are converted with; read by the worker at every pass boundary.
    display: Mutex<Display>,
    /// Whether noisy images are shown denoised; read like `display`.
    denoise: AtomicBool,
    /// Passes traced so far (previews included), for [`Controller::passes_traced`].
    passes: AtomicU64,
    /// The denoiser's feature buffers traced so far, for [`Controller::features_traced`].
    features_traced: AtomicU64,
    /// Test hook: the next pass panics inside the pool ([`Controller::inject_panic_on_next_pass`]).
    panic_next_pass: AtomicBool,
    notify: Notify,
}

impl Shared {
    fn current(&self) -> u64 {
        self.generation.load(Ordering::SeqCst)
    }

    fn display(&self) -> Display {
        *self.display.lock().unwrap_or_else(PoisonError::into_inner)
    }

    fn denoise(&self) -> bool {
        self.denoise.load(Ordering::SeqCst)
    }

    fn report(&self, error: WorkerError) {
        *self.error.lock().unwrap_or_else(PoisonError::into_inner) = Some(error);
        (self.notify)();
    }

    /// Panics if [`Controller::inject_panic_on_next_pass`] asked for it: called by every row of
    /// a pass, on the render pool's threads, so the panic takes the path a tracer bug would.
    /// A plain load first: the swap's write would bounce the flag between cores every row.
    fn injected_panic(&self) {
        if self.panic_next_pass.load(Ordering::Relaxed)
            && self.panic_next_pass.swap(false, Ordering::SeqCst)
        {
            panic!("{INJECTED_PANIC}");
        }
    }
}

/// Whether a frame converted with `a` looks like one converted with `b`: compared by bits, so
/// a NaN exposure equals itself and cannot make the worker publish at every pass.
fn same_display(a: &Display, b: &Display) -> bool {
    a.transform == b.transform && a.exposure.to_bits() == b.exposure.to_bits()
}

/// The progressive renderer: see the module docs.
pub struct Controller {
    shared: Arc<Shared>,
    sender: Sender<Message>,
    worker: Option<JoinHandle<()>>,
    threads: usize,
}

impl Controller {
    /// Starts the worker with a pool of `threads` render threads (0: one per core).
    pub fn new(threads: usize, notify: Notify) -> Result<Self, ControllerError> {
        let threads = resolve_threads(threads);
        let pool = build_pool(threads).map_err(ControllerError::Spawn)?;
        let shared = Arc::new(Shared {
            generation: AtomicU64::new(0),
            slot: Mutex::new(None),
            keep_every_frame: AtomicBool::new(false),
            taken: Condvar::new(),
            done: Mutex::new(0),
            done_changed: Condvar::new(),
            abandoned_jobs: AtomicU64::new(0),
            error: Mutex::new(None),
            display: Mutex::new(Display::default()),
            denoise: AtomicBool::new(false),
            passes: AtomicU64::new(0),
            features_traced: AtomicU64::new(0),
            panic_next_pass: AtomicBool::new(false),
            notify,
        });
        let (sender, receiver) = mpsc::channel();
        let worker_shared = Arc::clone(&shared);
        let worker = std::thread::Builder::new()
            .name("raylab-progressive".to_owned())
            .stack_size(crate::base::memory::WORKER_STACK_BYTES)
            .spawn(move || Worker::new(worker_shared, receiver, pool).run())
            .map_err(|e| ControllerError::Spawn(e.to_string()))?;
        Ok(Self {
            shared,
            sender,
            worker: Some(worker),
            threads,
        })
    }

    /// Starts a new job, making any running one stale. Returns its generation.
    ///
    /// Never blocks on the renderer: it takes only the frame slot's lock, which the worker holds
    /// just long enough to move a frame in.
    pub fn submit(
        &self,
        scene: &Arc<Scene>,
        settings: &RenderSettings,
    ) -> Result<u64, ControllerError> {
        settings.validate()?;
        let submitted = Instant::now();
        self.bump_and_send(|generation| Message::Job {
            generation,
            settings: Box::new(settings.clone()),
            scene: Arc::clone(scene),
            submitted,
        })
    }

    /// Rebuilds the render pool with `threads` threads (0: one per core) and restarts the
    /// current job on it.
    pub fn set_threads(&mut self, threads: usize) -> Result<u64, ControllerError> {
        let threads = resolve_threads(threads);
        self.threads = threads;
        self.bump_and_send(|generation| Message::Threads {
            generation,
            threads,
        })
    }

    /// Sets the display frames are converted with, from the next frame on: a running job shows
    /// it after its current pass, an idle one publishes its last frame again with it. Nothing is
    /// re-traced and the generation stays; setting the display in force does nothing.
    ///
    /// Never blocks on the renderer: the display's lock is only ever held to copy it.
    pub fn set_display(&self, display: Display) {
        {
            let mut current = self
                .shared
                .display
                .lock()
                .unwrap_or_else(PoisonError::into_inner);
            if same_display(&current, &display) {
                return;
            }
            *current = display;
        }
        // Stored before the message is sent, so the worker sees it when it wakes. A stopped
        // worker shows nothing anyway.
        let _ = self.sender.send(Message::Display);
    }

    /// The display in force.
    pub fn display(&self) -> Display {
        self.shared.display()
    }

    /// Shows noisy images ([`RenderSettings::is_stochastic`]) denoised, or not. Like a display
    /// change, it never restarts accumulation: a running job shows it at its next pass, an
    /// idle worker publishes its last frame again (denoising it then if it was not).
    pub fn set_denoise(&self, on: bool) {
        if self.shared.denoise.swap(on, Ordering::SeqCst) != on {
            let _ = self.sender.send(Message::Display);
        }
    }

    /// Whether noisy images are shown denoised.
    pub fn denoise(&self) -> bool {
        self.shared.denoise()
    }

    /// Passes traced since the controller started, previews included: a display change adds
    /// none.
    pub fn passes_traced(&self) -> u64 {
        self.shared.passes.load(Ordering::SeqCst)
    }

    /// The denoiser's feature buffers traced since the controller started: once for each view
    /// denoised (a job that only moves the light keeps its predecessor's).
    pub fn features_traced(&self) -> u64 {
        self.shared.features_traced.load(Ordering::SeqCst)
    }

    /// The number of render threads asked for.
    pub fn threads(&self) -> usize {
        self.threads
    }

    /// The newest generation handed out.
    pub fn generation(&self) -> u64 {
        self.shared.current()
    }

    /// The newest frame published since the last call, if any. Never waits: if the worker
    /// happens to hold the lock this instant, returns `None` (the worker's notify follows).
    pub fn take_frame(&self) -> Option<Frame> {
        let frame = match self.shared.slot.try_lock() {
            Ok(mut slot) => slot.take(),
            Err(std::sync::TryLockError::Poisoned(p)) => p.into_inner().take(),
            Err(std::sync::TryLockError::WouldBlock) => None,
        };
        if frame.is_some() {
            self.shared.taken.notify_all();
        }
        frame
    }

    /// Test hook: from now on the worker puts a frame in the slot only once the one before it
    /// was taken ([`Controller::take_frame`]) or went stale, so a test taking frames sees every
    /// frame a job publishes, however slowly it takes them. The window never sets it: the
    /// renderer would wait for its repaints.
    #[doc(hidden)]
    pub fn keep_every_frame(&self) {
        self.shared.keep_every_frame.store(true, Ordering::SeqCst);
    }

    /// A problem the worker met since the last call. Never waits (a held lock is tried again
    /// at the next call).
    pub fn take_error(&self) -> Option<WorkerError> {
        match self.shared.error.try_lock() {
            Ok(mut error) => error.take(),
            Err(std::sync::TryLockError::Poisoned(p)) => p.into_inner().take(),
            Err(std::sync::TryLockError::WouldBlock) => None,
        }
    }

    /// Test hook: the next pass traced (of the running job, or of the next one submitted)
    /// panics inside the render pool with [`INJECTED_PANIC`], as a bug in the tracer would, so
    /// tests exercise the real path: rayon re-raising it on the worker, which reports it.
    #[doc(hidden)]
    pub fn inject_panic_on_next_pass(&self) {
        self.shared.panic_next_pass.store(true, Ordering::SeqCst);
    }

    /// Jobs abandoned so far, before their target, because a newer one arrived.
    pub fn abandoned_jobs(&self) -> u64 {
        self.shared.abandoned_jobs.load(Ordering::SeqCst)
    }

    /// Blocks until the newest job has reached its sample target (or panicked: see
    /// [`Controller::take_error`]), or `timeout` passes. Returns whether it finished. For tests
    /// and scripts: **never call this on the UI thread**.
    pub fn wait_idle(&self, timeout: Duration) -> bool {
        let deadline = Instant::now() + timeout;
        let mut done = self
            .shared
            .done
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        loop {
            if *done >= self.shared.current() {
                return true;
            }
            let now = Instant::now();
            if now >= deadline {
                return false;
            }
            done = match self.shared.done_changed.wait_timeout(done, deadline - now) {
                Ok((guard, _)) => guard,
                Err(p) => p.into_inner().0,
            };
        }
    }

    fn bump_and_send(&self, message: impl FnOnce(u64) -> Message) -> Result<u64, ControllerError> {
        // Bump under the slot's lock, and drop any frame the UI has not taken yet: it is stale.
        let mut slot = self
            .shared
            .slot
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        let generation = self.shared.generation.fetch_add(1, Ordering::SeqCst) + 1;
        *slot = None;
        self.sender
            .send(message(generation))
            .map_err(|_| ControllerError::Stopped)?;
        Ok(generation)
    }
}

impl Drop for Controller {
    fn drop(&mut self) {
        // Cancel the running pass, then let the worker leave its loop.
        self.shared.generation.fetch_add(1, Ordering::SeqCst);
        let _ = self.sender.send(Message::Quit);
        if let Some(worker) = self.worker.take() {
            let _ = worker.join();
        }
    }
}

fn resolve_threads(threads: usize) -> usize {
    if threads == 0 {
        default_threads()
    } else {
        threads.min(MAX_THREADS)
    }
}

/// The most render threads a pool is built with (`--threads` takes 1 to this): far more than
/// any machine's cores, and few enough that starting them is quick.
pub const MAX_THREADS: usize = 1024;

/// The most threads a core `RAYON_NUM_THREADS` may ask for. More only wait for a core, and
/// starting a thousand of them costs more than a small render (an explicit `--threads` is
/// taken up to [`MAX_THREADS`]).
pub const THREADS_PER_CORE: usize = 4;

/// The render threads when none are asked for: `RAYON_NUM_THREADS` if it is set to a number
/// (at most [`THREADS_PER_CORE`] a core), else one per core. Every pool raylab builds is given
/// its count explicitly, so rayon's own reading of `RAYON_NUM_THREADS`, which has no cap,
/// never applies.
pub fn default_threads() -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    threads_from(std::env::var("RAYON_NUM_THREADS").ok().as_deref(), cores).0
}

/// What `RAYON_NUM_THREADS` set to something unusable makes of [`default_threads`], for a
/// warning: `None` when it is unset or a number from 1 to [`THREADS_PER_CORE`] a core.
pub fn default_threads_note() -> Option<String> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    threads_from(std::env::var("RAYON_NUM_THREADS").ok().as_deref(), cores).1
}

/// The thread count for a `RAYON_NUM_THREADS` value on a machine of `cores`, and a note when
/// the value was not used as it stands.
fn threads_from(variable: Option<&str>, cores: usize) -> (usize, Option<String>) {
    let cores = cores.clamp(1, MAX_THREADS);
    let cap = (THREADS_PER_CORE * cores).min(MAX_THREADS);
    let Some(text) = variable else {
        return (cores, None);
    };
    match text.trim().parse::<u128>() {
        // rayon's own meaning of 0: one per core.
        Ok(0) => (cores, None),
        Ok(n) if n <= cap as u128 => (n as usize, None),
        Ok(_) => (
            cap,
            Some(format!(
                "RAYON_NUM_THREADS={} is more than {THREADS_PER_CORE} threads a core: using \
                 {cap} ({cores} core{})",
                text.trim(),
                if cores == 1 { "" } else { "s" }
            )),
        ),
        Err(_) => (
            cores,
            Some(format!(
                "RAYON_NUM_THREADS={text:?} is not a number of threads: using one per core \
                 ({cores})"
            )),
        ),
    }
}

fn build_pool(threads: usize) -> Result<rayon::ThreadPool, String> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("raylab-render-{i}"))
        .stack_size(crate::base::memory::WORKER_STACK_BYTES)
        .build()
        .map_err(|e| e.to_string())
}

/// The size of the coarse preview for a `width × height` image, or `None` to skip it.
pub fn preview_size(width: u32, height: u32) -> Option<(u32, u32)> {
    if width.max(height) < PREVIEW_MIN_SIDE {
        return None;
    }
    Some((
        (width / PREVIEW_DIVISOR).max(1),
        (height / PREVIEW_DIVISOR).max(1),
    ))
}

struct Job {
    generation: u64,
    settings: RenderSettings,
    scene: Arc<Scene>,
    submitted: Instant,
}

struct Worker {
    shared: Arc<Shared>,
    receiver: Receiver<Message>,
    pool: rayon::ThreadPool,
    /// The newest job, kept so a thread change can restart it.
    job: Option<Job>,
    /// The last frame published, without its `rgba` (the linear image is shared with the UI's
    /// copy through the `Arc`), so a display change can publish it again without tracing.
    last: Option<Frame>,
    /// The running job's [`Frame::camera_note`].
    camera_note: Option<String>,
    /// The running (or last) job's denoising.
    denoising: Denoising,
}

/// What the worker keeps to denoise a job's frames: the features, traced when first needed and
/// kept by the next job if they serve its view too ([`Features::serve`]: moving the light
/// keeps them); the variance of the last frame's mean; the last denoised image and what it
/// cost.
#[derive(Default)]
struct Denoising {
    /// The features, and the scene and settings they were traced for.
    features: Option<(Arc<Features>, Arc<Scene>, RenderSettings)>,
    variance: Option<Arc<Vec<f32>>>,
    /// The film of the last job that ran to its end.
    film: Option<Film>,
    /// The features this job's film recorded, and of how many samples.
    recorded: Option<(u32, Arc<Features>)>,
    image: Option<Arc<Image>>,
    /// `image`'s estimated error.
    error: Option<f64>,
    samples: u32,
    cost: Duration,
    at: Option<Instant>,
}

/// How long after one denoising the next may start between doublings of the samples, as a
/// multiple of its cost ([`denoise_due`]): there the denoiser takes at most a tenth of the
/// worker's time. (Early in a job the doublings come faster and may take more.)
const DENOISE_SPACING: u32 = 9;

/// Whether a job's image is denoised after its pass `samples` (counted from 1), the last pass
/// aside (always denoised), given `last`, the samples of the job's last denoised image and the
/// time since it (`None` if none yet), the denoising's `cost` and the time a `pass` takes:
///
/// * never after the first pass, which is shown raw at once;
/// * at every doubling of the samples (2, 4, 8, 16, …): each halves the raw image's variance,
///   and the denoised image keeps up with it without delay (16 samples denoised are about as
///   clean as 256 raw ones: PERFORMANCE.md, "The denoiser"; shown as soon as the sixteenth
///   pass is in);
/// * between doublings, once the last denoising is [`DENOISE_SPACING`] times its cost ago,
///   the samples have grown by a quarter since it, and the next doubling is farther off than
///   the spacing at `pass` a pass. So the denoiser takes at most a tenth of the time, and less
///   and less as the image converges (a quarter more samples lower its noise by about a
///   tenth).
pub fn denoise_due(
    samples: u32,
    last: Option<(u32, Duration)>,
    cost: Duration,
    pass: Duration,
) -> bool {
    if samples < 2 {
        return false;
    }
    if samples.is_power_of_two() {
        return true;
    }
    let spacing = cost * DENOISE_SPACING;
    let to_doubling = pass * (samples.next_power_of_two() - samples);
    let since_last = last.is_none_or(|(denoised, since)| {
        since >= spacing && u64::from(samples) * 4 >= u64::from(denoised) * 5
    });
    since_last && to_doubling >= spacing
}

impl Worker {
    fn new(shared: Arc<Shared>, receiver: Receiver<Message>, pool: rayon::ThreadPool) -> Self {
        Self {
            shared,
            receiver,
            pool,
            job: None,
            last: None,
            camera_note: None,
            denoising: Denoising::default(),
        }
    }

    fn run(mut self) {
        // Wait (asleep) for a message, then take every message already queued: only the newest
        // job matters.
        while let Ok(first) = self.receiver.recv() {
            let mut pending = Some(first);
            let mut run = false;
            let mut redisplay = false;
            while let Some(message) = pending.take() {
                match message {
                    Message::Quit => return,
                    Message::Job {
                        generation,
                        settings,
                        scene,
                        submitted,
                    } => {
                        self.job = Some(Job {
                            generation,
                            settings: *settings,
                            scene,
                            submitted,
                        });
                        run = true;
                    }
                    Message::Threads {
                        generation,
                        threads,
                    } => {
                        self.rebuild_pool(threads);
                        if let Some(job) = &mut self.job {
                            job.generation = generation;
                            job.submitted = Instant::now();
                            run = true;
                        } else {
                            self.mark_done(generation);
                        }
                    }
                    Message::Display => redisplay = true,
                }
                pending = match self.receiver.try_recv() {
                    Ok(m) => Some(m),
                    Err(TryRecvError::Empty) => None,
                    Err(TryRecvError::Disconnected) => return,
                };
            }
            // A job to render shows the display in force anyway.
            if run && let Some(job) = self.job.take() {
                match catch_panic(|| self.render_job(&job)) {
                    Ok(true) => self.mark_done(job.generation),
                    Ok(false) => {
                        self.shared.abandoned_jobs.fetch_add(1, Ordering::SeqCst);
                    }
                    Err(panic) => {
                        self.drop_frames_of(job.generation);
                        self.shared.report(WorkerError {
                            message: format!(
                                "The render panicked: {panic} (settings: {})",
                                job.settings.summary()
                            ),
                            settings: Some(job.settings.clone()),
                        });
                        // Nothing more will come of it: `wait_idle` need not wait.
                        self.mark_done(job.generation);
                    }
                }
                // Kept even after a panic: a thread change renders it again, as asked.
                self.job = Some(job);
            } else if redisplay && let Err(panic) = catch_panic(|| self.redisplay()) {
                self.shared.report(WorkerError {
                    message: format!("Showing the image with the new display panicked: {panic}"),
                    settings: None,
                });
            }
        }
    }

    /// Publishes the last frame again with the display in force, if it was shown with another.
    /// Its generation, samples, linear image and timings stay: nothing is traced. If a newer
    /// submission has come since, `publish` refuses it (that job will show the new display).
    fn redisplay(&mut self) {
        let display = self.shared.display();
        let denoise = self.shared.denoise();
        let Some(last) = self.last.clone() else {
            return;
        };
        if same_display(&last.display, &display) && last.denoise == denoise {
            return;
        }
        // Turned on after the job: its last frame is denoised now, if it is a noisy one.
        let denoisable = !last.is_preview && last.legend.is_none() && last.settings.is_stochastic();
        let mut denoised = last.denoised.clone();
        if denoise && denoised.is_none() && denoisable && self.denoising.variance.is_some() {
            let job = Job {
                generation: last.generation,
                settings: last.settings.clone(),
                scene: match &self.job {
                    Some(job) if job.generation == last.generation => Arc::clone(&job.scene),
                    _ => return,
                },
                submitted: Instant::now(),
            };
            let film = self.denoising.film.take();
            let result = self.denoise(&job, film.as_ref(), &last.image, last.samples);
            self.denoising.film = film;
            if result.is_err() {
                return;
            }
            denoised = self.denoising.image.clone();
        }
        let shown = shown_with(display, last.legend.as_ref());
        let source = match (&denoised, denoise) {
            (Some(denoised), true) => Arc::clone(denoised),
            _ => Arc::clone(&last.image),
        };
        let frame = Frame {
            rgba: self.pool.install(|| shown.to_rgba8(&source.pixels)),
            display,
            denoise,
            denoised_samples: if denoised.is_some() && last.denoised.is_none() {
                self.denoising.samples
            } else {
                last.denoised_samples
            },
            denoised_error: if denoised.is_some() && last.denoised.is_none() {
                self.denoising.error
            } else {
                last.denoised_error
            },
            denoise_ms: if denoised.is_some() && last.denoised.is_none() {
                self.denoising.cost.as_secs_f64() * 1e3
            } else {
                last.denoise_ms
            },
            denoised,
            ..last
        };
        self.publish_and_keep(frame);
    }

    fn rebuild_pool(&mut self, threads: usize) {
        match build_pool(threads) {
            Ok(pool) => self.pool = pool,
            Err(e) => self.shared.report(WorkerError {
                message: format!("could not start {threads} render threads: {e}"),
                settings: None,
            }),
        }
    }

    /// After a panic: nothing of generation `generation` is shown any more, neither a frame it
    /// published that the UI has not taken yet, nor (for a display change) its last frame.
    fn drop_frames_of(&mut self, generation: u64) {
        let mut slot = self
            .shared
            .slot
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        if slot.as_ref().is_some_and(|f| f.generation == generation) {
            *slot = None;
        }
        if self
            .last
            .as_ref()
            .is_some_and(|f| f.generation == generation)
        {
            self.last = None;
        }
    }

    fn mark_done(&self, generation: u64) {
        let mut done = self
            .shared
            .done
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        *done = (*done).max(generation);
        self.shared.done_changed.notify_all();
    }

    /// Renders the job's preview and passes up to its target. Returns `false` if a newer job
    /// made it stale on the way.
    fn render_job(&mut self, job: &Job) -> bool {
        let shared = Arc::clone(&self.shared);
        let stale = || shared.current() != job.generation;
        let settings = &job.settings;
        let target = settings.samples_per_pixel.max(1);
        let (width, height) = (settings.camera.width, settings.camera.height);
        self.camera_note = camera_sees_nothing(&job.scene, settings);
        // A new job starts its denoising afresh, keeping the features if its view is theirs.
        let features = self
            .denoising
            .features
            .take()
            .filter(|(_, scene, traced_for)| {
                Arc::ptr_eq(scene, &job.scene) && Features::serve(traced_for, settings)
            });
        self.denoising = Denoising {
            features,
            ..Denoising::default()
        };

        if settings.view.is_traced() {
            // A debug view: one ray per pixel centre, once.
            let start = Instant::now();
            let cancelled = || {
                shared.injected_panic();
                shared.current() != job.generation
            };
            let result = self
                .pool
                .install(|| render_view(&job.scene, settings, settings.view, &cancelled));
            let Ok(view) = result else {
                return false;
            };
            let ms = start.elapsed().as_secs_f64() * 1e3;
            let rays = u64::from(width) * u64::from(height);
            let legend = Some(view.legend);
            let mut frame = self.frame(job, view.image, target, false, ms, rays, None, legend);
            self.convert(&mut frame);
            return self.publish_and_keep(frame);
        }

        if let Some((w, h)) = preview_size(width, height) {
            let mut preview = settings.clone();
            preview.camera = settings.camera.with_resolution(w, h);
            let Some((image, pass_ms)) = self.pass(job, &preview, 0) else {
                return false;
            };
            let rays = u64::from(w) * u64::from(h);
            let mut frame = self.frame(job, image, 0, true, pass_ms, rays, None, None);
            self.convert(&mut frame);
            if !self.publish_and_keep(frame) {
                return false;
            }
        }

        // The path tracer's samples also tell the film what they saw: the denoiser's features.
        let mut film = denoising_film(&job.scene, settings);
        let accumulating = Instant::now();
        let mut published = accumulating;
        for sample in 0..target {
            let Some(pass_ms) = self.accumulate(job, settings, sample, &mut film) else {
                return false;
            };
            // Short passes are not all shown, and fewer as the job goes on
            // ([`frame_interval`]). The first and the last always are, the first after a
            // display change, so the change shows within one pass, and those denoised (every
            // doubling of the samples among them: [`denoise_due`]). While a denoised image
            // stays on screen unchanged, only its figures (samples, noise) would change: those
            // frames come at most every MAX_FRAME_INTERVAL, and the time a repaint takes goes
            // to the passes.
            let last = sample + 1 == target;
            let denoising = settings.is_stochastic()
                && settings.view != View::Variance
                && self.shared.denoise();
            let pass = Duration::from_secs_f64(pass_ms / 1e3);
            let before = (self.denoising.at).map(|at| (self.denoising.samples, at.elapsed()));
            let due =
                denoising && (last || denoise_due(sample + 1, before, self.denoising.cost, pass));
            let interval = if denoising && self.denoising.image.is_some() {
                MAX_FRAME_INTERVAL
            } else {
                frame_interval(accumulating.elapsed())
            };
            if sample > 0
                && !last
                && !due
                && published.elapsed() < interval
                && !self.display_changed()
            {
                continue;
            }
            published = Instant::now();
            // The variance view: each pixel's variance of the mean, once there are two samples.
            let variance = if settings.view == View::Variance {
                variance_view(&film).map(|v| (v.image, v.legend))
            } else {
                None
            };
            let (image, legend) = match variance {
                Some((image, legend)) => (image, Some(legend)),
                None => (self.pool.install(|| film.resolve()), None),
            };
            if stale() {
                return false;
            }
            let rays = u64::from(width) * u64::from(height);
            let noise = self.pool.install(|| film.noise());
            // A noisy shaded image keeps its variance for the denoiser, and is denoised if the
            // denoiser is on and it is due (always for the last frame).
            let denoised = if settings.is_stochastic() && legend.is_none() {
                self.denoising.variance = self.pool.install(|| film.variance()).map(Arc::new);
                // Not the first full pass (unless it is the last): it is shown at once, raw,
                // where tracing the features (once a view) would hold it back; then at every
                // doubling of the samples, and spaced between them.
                if due && self.denoise(job, Some(&film), &image, sample + 1).is_err() {
                    return false;
                }
                self.denoising.image.clone()
            } else {
                None
            };
            let mut frame = self.frame(job, image, sample + 1, false, pass_ms, rays, noise, legend);
            if let Some(denoised) = denoised {
                frame = self.with_denoised(frame, denoised);
            } else {
                self.convert(&mut frame);
            }
            if !self.publish_and_keep(frame) {
                return false;
            }
        }
        // Kept for the last frame's features, should the denoiser be turned on after the job.
        self.denoising.film = Some(film);
        true
    }

    /// Denoises `image`, the mean of `samples` passes of `job` (those of `film`, if it is
    /// there), whose variance `self.denoising` holds, with the features `film` recorded, or
    /// else traced (if this job has none yet); the result goes into `self.denoising`. `Err` if
    /// the job went stale meanwhile.
    fn denoise(
        &mut self,
        job: &Job,
        film: Option<&Film>,
        image: &Image,
        samples: u32,
    ) -> Result<(), Cancelled> {
        let shared = &self.shared;
        let cancelled = || shared.current() != job.generation;
        let denoising = &mut self.denoising;
        // The denoising's cost: the filter and the averaging of recorded features, not the
        // tracing of features once a view.
        let mut start = Instant::now();
        // The features the film recorded, averaged again only if it recorded more since: from
        // its 64th sample on they stay.
        let recorded = film.and_then(|film| {
            let (_, count) = film.seen()?;
            match &denoising.recorded {
                Some((done, features)) if *done == count => Some(Arc::clone(features)),
                _ => {
                    let features = Arc::new(self.pool.install(|| Features::recorded(film))?);
                    denoising.recorded = Some((count, Arc::clone(&features)));
                    Some(features)
                }
            }
        });
        let features = match (recorded, &denoising.features) {
            (Some(recorded), _) => recorded,
            (None, Some((features, _, _))) => Arc::clone(features),
            (None, None) => {
                let traced = self
                    .pool
                    .install(|| Features::trace(&job.scene, &job.settings, &cancelled))?;
                shared.features_traced.fetch_add(1, Ordering::SeqCst);
                let traced = Arc::new(traced);
                let scene = Arc::clone(&job.scene);
                denoising.features = Some((Arc::clone(&traced), scene, job.settings.clone()));
                start = Instant::now();
                traced
            }
        };
        let variance = denoising.variance.clone();
        let (denoised, error) = self.pool.install(|| {
            // The film's outliers are taken apart where the film is the image's own.
            let noisy = match film {
                Some(film) if film.samples() == samples => Noisy::of_film(film),
                _ => Noisy::whole(image.clone(), variance.as_deref().cloned()),
            };
            let denoiser = Denoiser::default();
            let denoised = denoiser.denoise_noisy(&noisy, &features);
            // What the screen shows is the denoised image: its own error, from a second
            // filtering of the same colour moved a little (the outliers' light, given back
            // after the filter, is the same in both), counted in the cost, so the spacing of
            // denoisings allows for it.
            let error = noisy.variance.as_deref().map(|v| {
                estimated_error(&noisy.colour, v, &denoised, |moved| {
                    let moved = Noisy {
                        colour: moved.clone(),
                        ..noisy.clone()
                    };
                    denoiser.denoise_noisy(&moved, &features)
                })
            });
            (denoised, error)
        });
        denoising.cost = start.elapsed();
        denoising.at = Some(Instant::now());
        denoising.image = Some(Arc::new(denoised));
        denoising.error = error;
        denoising.samples = samples;
        if cancelled() { Err(Cancelled) } else { Ok(()) }
    }

    /// `frame` with the denoised image `denoised` (of `self.denoising`), converted for the
    /// screen if the denoiser is on (else `frame`'s own image is): one conversion a frame.
    fn with_denoised(&self, frame: Frame, denoised: Arc<Image>) -> Frame {
        let on = self.shared.denoise();
        let shown = shown_with(frame.display, frame.legend.as_ref());
        let source = if on { &denoised } else { &frame.image };
        let rgba = self.pool.install(|| shown.to_rgba8(&source.pixels));
        Frame {
            rgba,
            denoise: on,
            denoised_samples: self.denoising.samples,
            denoised_error: self.denoising.error,
            denoise_ms: self.denoising.cost.as_secs_f64() * 1e3,
            denoised: Some(denoised),
            ..frame
        }
    }

    /// Whether the display in force differs from the last frame's.
    fn display_changed(&self) -> bool {
        self.last.as_ref().is_some_and(|last| {
            !same_display(&last.display, &self.shared.display())
                || last.denoise != self.shared.denoise()
        })
    }

    /// One pass, or `None` if the job went stale.
    fn pass(&self, job: &Job, settings: &RenderSettings, sample: u32) -> Option<(Image, f64)> {
        self.run_pass(job, |cancelled| {
            render_pass(&job.scene, settings, sample, cancelled)
        })
    }

    /// One pass added into `film`, or `None` if the job went stale (the film then holds part
    /// of the pass: the job is over). Returns the pass's time in milliseconds.
    fn accumulate(
        &self,
        job: &Job,
        settings: &RenderSettings,
        sample: u32,
        film: &mut Film,
    ) -> Option<f64> {
        self.run_pass(job, |cancelled| {
            accumulate_pass(&job.scene, settings, sample, film, cancelled)
        })
        .map(|((), ms)| ms)
    }

    /// Runs a pass, `trace`, on the pool with the job's cancellation (asked by every row, on
    /// the pool's threads), and counts it; `None` if the job went stale before or during it.
    /// Returns its result and its time in milliseconds.
    fn run_pass<T: Send>(
        &self,
        job: &Job,
        trace: impl FnOnce(&(dyn Fn() -> bool + Sync)) -> Result<T, Cancelled> + Send,
    ) -> Option<(T, f64)> {
        let shared = &self.shared;
        if shared.current() != job.generation {
            return None;
        }
        let cancelled = || {
            shared.injected_panic();
            shared.current() != job.generation
        };
        let start = Instant::now();
        match self.pool.install(|| trace(&cancelled)) {
            Ok(value) => {
                shared.passes.fetch_add(1, Ordering::SeqCst);
                Some((value, start.elapsed().as_secs_f64() * 1e3))
            }
            Err(Cancelled) => None,
        }
    }

    /// A frame of `job` showing `image`, its pixels not yet converted for the screen
    /// ([`Worker::convert`], or [`Worker::with_denoised`]).
    #[allow(clippy::too_many_arguments)]
    fn frame(
        &self,
        job: &Job,
        image: Image,
        samples: u32,
        is_preview: bool,
        pass_ms: f64,
        rays: u64,
        noise: Option<NoiseEstimate>,
        legend: Option<Legend>,
    ) -> Frame {
        let display = self.shared.display();
        Frame {
            generation: job.generation,
            settings: job.settings.clone(),
            image: Arc::new(image),
            denoised: None,
            denoised_samples: 0,
            denoised_error: None,
            denoise_ms: 0.0,
            denoise: self.shared.denoise(),
            rgba: Vec::new(),
            display,
            samples,
            target: job.settings.samples_per_pixel.max(1),
            is_preview,
            pass_ms,
            mrays_per_s: if pass_ms > 0.0 {
                rays as f64 / (pass_ms * 1e3)
            } else {
                0.0
            },
            since_submit_ms: job.submitted.elapsed().as_secs_f64() * 1e3,
            noise,
            legend,
            camera_note: self.camera_note.clone(),
        }
    }

    /// `frame`'s linear image converted for the screen through its display ([`Frame::rgba`]).
    fn convert(&self, frame: &mut Frame) {
        let shown = shown_with(frame.display, frame.legend.as_ref());
        frame.rgba = self.pool.install(|| shown.to_rgba8(&frame.image.pixels));
    }

    /// [`Worker::publish`], remembering the frame (without its pixels) for a display change.
    fn publish_and_keep(&mut self, mut kept: Frame) -> bool {
        // Cloned without its pixels: they may be tens of megabytes.
        let rgba = std::mem::take(&mut kept.rgba);
        let published = self.publish(Frame {
            rgba,
            ..kept.clone()
        });
        if published {
            self.last = Some(kept);
        }
        published
    }

    /// Puts the frame in the slot unless its generation is stale; returns whether it did.
    fn publish(&self, frame: Frame) -> bool {
        {
            let mut slot = self
                .shared
                .slot
                .lock()
                .unwrap_or_else(PoisonError::into_inner);
            // With `keep_every_frame`, wait for the last frame to be taken. The wait is woken
            // by `take_frame`, and ends within its timeout once a submission or the
            // controller's drop made this frame stale.
            while slot.is_some()
                && self.shared.keep_every_frame.load(Ordering::SeqCst)
                && self.shared.current() == frame.generation
            {
                slot = match self
                    .shared
                    .taken
                    .wait_timeout(slot, Duration::from_millis(10))
                {
                    Ok((guard, _)) => guard,
                    Err(p) => p.into_inner().0,
                };
            }
            // `submit` bumps the generation under this lock: checked here, no newer submission
            // can slip in before the frame is in place.
            if self.shared.current() != frame.generation {
                return false;
            }
            *slot = Some(frame);
        }
        (self.shared.notify)();
        true
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::AtomicUsize;

    use super::*;
    use crate::shapes::scene::cornell_box;
    use crate::transport::display::DisplayTransform;
    use crate::transport::render::render;

    const TIMEOUT: Duration = Duration::from_secs(60);

    fn small(width: u32, height: u32, samples: u32) -> RenderSettings {
        let mut s = RenderSettings::default();
        s.camera = s.camera.with_resolution(width, height);
        s.samples_per_pixel = samples;
        s
    }

    /// [`small`] on the path stage, the noisy image the denoiser is for.
    fn small_path(width: u32, height: u32, samples: u32) -> RenderSettings {
        let mut s = small(width, height, samples);
        s.shading = crate::Shading::for_stage(crate::Stage::Path);
        s
    }

    fn quiet() -> Notify {
        Box::new(|| {})
    }

    /// Submits `settings` and waits for the job's last frame and for the worker to go idle.
    fn finished(controller: &Controller, scene: &Arc<Scene>, settings: &RenderSettings) -> Frame {
        let g = controller.submit(scene, settings).unwrap();
        let frame = last_frame(controller, g);
        assert!(controller.wait_idle(TIMEOUT));
        frame
    }

    /// The frames of job `generation` taken as they come, up to its final one, and the worker
    /// idle after it (the UI would see only the newest of a burst; polled this often, few are
    /// missed).
    fn every_frame(controller: &Controller, generation: u64) -> Vec<Frame> {
        let mut frames: Vec<Frame> = Vec::new();
        let deadline = Instant::now() + TIMEOUT;
        while frames.last().is_none_or(|f| !f.is_final()) {
            if let Some(f) = controller
                .take_frame()
                .filter(|f| f.generation == generation)
            {
                frames.push(f);
            }
            assert!(
                Instant::now() < deadline,
                "no final frame within {TIMEOUT:?}"
            );
            std::thread::yield_now();
        }
        assert!(controller.wait_idle(TIMEOUT));
        frames
    }

    /// Takes frames until one is final for `generation`, checking the order on the way.
    fn last_frame(controller: &Controller, generation: u64) -> Frame {
        let deadline = Instant::now() + TIMEOUT;
        let mut newest_seen = 0;
        loop {
            if let Some(frame) = controller.take_frame() {
                assert!(frame.generation >= newest_seen, "an older frame came later");
                newest_seen = frame.generation;
                if frame.generation == generation && frame.is_final() {
                    return frame;
                }
            }
            assert!(
                Instant::now() < deadline,
                "no final frame within {TIMEOUT:?}"
            );
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    /// The denoiser's schedule, worked out by hand: a denoising of 30 ms may come again 9 × 30
    /// = 270 ms later, at passes of 60 ms.
    #[test]
    fn denoising_comes_at_every_doubling_and_spaced_between() {
        let ms = Duration::from_millis;
        let (cost, pass) = (ms(30), ms(60));
        // The first pass is shown raw; each doubling is denoised whatever came before.
        assert!(!denoise_due(1, None, cost, pass));
        for samples in [2, 4, 8, 16, 64, 1024] {
            assert!(denoise_due(samples, Some((samples - 1, ms(1))), cost, pass));
        }
        // Pass 21, the last denoising at 16 samples 300 ms ago (≥ 270; 21 ≥ 1.25 · 16) and
        // 32 eleven passes, 660 ms, off: due.
        assert!(denoise_due(21, Some((16, ms(300))), cost, pass));
        // Only 100 ms after the last: not yet.
        assert!(!denoise_due(21, Some((16, ms(100))), cost, pass));
        // Pass 19: less than a quarter more samples than 16 (19 < 20).
        assert!(!denoise_due(19, Some((16, ms(300))), cost, pass));
        assert!(denoise_due(20, Some((16, ms(300))), cost, pass));
        // Pass 13: 16 is 3 passes, 180 ms, off (< 270): left to the doubling.
        assert!(!denoise_due(13, Some((8, ms(400))), cost, pass));
        // Pass 300 after 256: a quarter more is 320.
        assert!(!denoise_due(300, Some((256, ms(5_000))), cost, pass));
        assert!(denoise_due(320, Some((256, ms(5_000))), cost, pass));
        // Pass 33 with none yet this job: 64 is 31 passes off.
        assert!(denoise_due(33, None, cost, pass));
    }

    #[test]
    fn previews_then_accumulates_to_the_target() {
        let scene = Arc::new(cornell_box());
        let notified = Arc::new(AtomicUsize::new(0));
        let n = Arc::clone(&notified);
        let controller =
            Controller::new(2, Box::new(move || _ = n.fetch_add(1, Ordering::SeqCst))).unwrap();
        let settings = small(96, 64, 4);
        let generation = controller.submit(&scene, &settings).unwrap();
        let frames = every_frame(&controller, generation);
        let last = frames.last().unwrap();
        assert_eq!(last.generation, generation);
        assert_eq!((last.samples, last.target), (4, 4));
        assert_eq!((last.image.width, last.image.height), (96, 64));
        assert_eq!(last.rgba.len(), 96 * 64 * 4);
        assert_eq!(*last.image, render(&scene, &settings));
        if let Some(first) = frames.first().filter(|f| f.is_preview) {
            assert_eq!((first.image.width, first.image.height), (12, 8));
        }
        // Sample counts only grow.
        assert!(frames.windows(2).all(|w| w[0].samples <= w[1].samples));
        assert!(notified.load(Ordering::SeqCst) >= 1);
    }

    #[test]
    fn a_newer_job_cancels_an_older_one() {
        let scene = Arc::new(cornell_box());
        let controller = Controller::new(1, quiet()).unwrap();
        // A job far too long to finish within the test: 512², 4096 samples.
        let old = controller.submit(&scene, &small(512, 512, 4096)).unwrap();
        // Wait until it is into its full-resolution passes.
        let deadline = Instant::now() + TIMEOUT;
        loop {
            if controller.take_frame().is_some_and(|f| !f.is_preview) {
                break;
            }
            assert!(Instant::now() < deadline, "the old job never got going");
            std::thread::sleep(Duration::from_millis(1));
        }
        let newer = small(32, 32, 2);
        let generation = controller.submit(&scene, &newer).unwrap();
        assert!(generation > old);
        let frame = last_frame(&controller, generation);
        assert_eq!(frame.settings, newer);
        assert!(controller.wait_idle(TIMEOUT));
        // The old job was abandoned, not run to its end (4096 passes of 512²): the worker
        // says so, and traced far fewer passes than it asked for.
        assert_eq!(controller.abandoned_jobs(), 1);
        assert!(
            controller.passes_traced() < 4096,
            "{}",
            controller.passes_traced()
        );
        // And it publishes nothing more: the worker is idle on the newest job.
        std::thread::sleep(Duration::from_millis(50));
        assert!(controller.take_frame().is_none());
    }

    #[test]
    fn after_1000_rapid_changes_the_last_settings_win() {
        let scene = Arc::new(cornell_box());
        let controller = Controller::new(2, quiet()).unwrap();
        let mut settings = small(48, 32, 2);
        let mut newest_seen = 0;
        let mut generation = 0;
        for i in 0..1000 {
            settings.light.position.x = -0.8 + 1.6 * i as f32 / 999.0;
            generation = controller.submit(&scene, &settings).unwrap();
            // The UI polls between changes: whatever it sees is never older than before.
            if let Some(frame) = controller.take_frame() {
                assert!(frame.generation >= newest_seen);
                newest_seen = frame.generation;
            }
        }
        let frame = last_frame(&controller, generation);
        assert_eq!(frame.settings, settings);
        assert_eq!(*frame.image, render(&scene, &settings));
        assert!(controller.wait_idle(TIMEOUT));
        assert!(controller.take_frame().is_none());
    }

    #[test]
    fn the_same_settings_give_the_same_image() {
        let scene = Arc::new(cornell_box());
        let settings = small(40, 40, 3);
        let images: Vec<Arc<Image>> = [1, 2]
            .into_iter()
            .map(|threads| {
                let controller = Controller::new(threads, quiet()).unwrap();
                let generation = controller.submit(&scene, &settings).unwrap();
                last_frame(&controller, generation).image
            })
            .collect();
        assert_eq!(images[0], images[1]);
        // A third run on a controller that rendered something else first.
        let controller = Controller::new(2, quiet()).unwrap();
        let other = small(40, 40, 1);
        let g = controller.submit(&scene, &other).unwrap();
        last_frame(&controller, g);
        let g = controller.submit(&scene, &settings).unwrap();
        assert_eq!(last_frame(&controller, g).image, images[0]);
    }

    #[test]
    fn changing_threads_restarts_the_job() {
        let scene = Arc::new(cornell_box());
        let mut controller = Controller::new(1, quiet()).unwrap();
        let settings = small(32, 32, 2);
        let g = controller.submit(&scene, &settings).unwrap();
        last_frame(&controller, g);
        let g = controller.set_threads(2).unwrap();
        assert_eq!(controller.threads(), 2);
        let frame = last_frame(&controller, g);
        assert_eq!(*frame.image, render(&scene, &settings));
    }

    #[test]
    fn invalid_settings_are_refused_before_any_work() {
        let controller = Controller::new(1, quiet()).unwrap();
        let mut s = small(16, 16, 1);
        s.camera.focal_length = 0.0;
        let scene = Arc::new(cornell_box());
        assert!(matches!(
            controller.submit(&scene, &s),
            Err(ControllerError::Invalid(_))
        ));
        assert_eq!(controller.generation(), 0);
    }

    /// The next frame published, waiting for it.
    fn next_frame(controller: &Controller) -> Frame {
        let deadline = Instant::now() + TIMEOUT;
        loop {
            if let Some(frame) = controller.take_frame() {
                return frame;
            }
            assert!(Instant::now() < deadline, "no frame within {TIMEOUT:?}");
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    const BRIGHTER: Display = Display {
        transform: DisplayTransform::Lab,
        exposure: 1.0,
    };

    #[test]
    fn a_display_change_when_idle_publishes_the_last_frame_again() {
        let scene = Arc::new(cornell_box());
        let controller = Controller::new(2, quiet()).unwrap();
        let g = controller.submit(&scene, &small(32, 32, 3)).unwrap();
        let before = last_frame(&controller, g);
        assert!(controller.wait_idle(TIMEOUT));
        assert_eq!(before.display, Display::default());
        assert_eq!(before.rgba, before.image.to_rgba8());
        // Three passes, no preview (32 < 64).
        assert_eq!(controller.passes_traced(), 3);

        controller.set_display(BRIGHTER);
        assert_eq!(controller.display(), BRIGHTER);
        let after = next_frame(&controller);
        assert_eq!((after.generation, after.samples, after.target), (g, 3, 3));
        assert!(after.is_final());
        assert_eq!(after.display, BRIGHTER);
        assert_eq!(after.rgba, BRIGHTER.to_rgba8(&after.image.pixels));
        assert_ne!(after.rgba, before.rgba);
        // Nothing traced: the same linear image, the same pass, no pass added.
        assert!(Arc::ptr_eq(&after.image, &before.image));
        assert_eq!(after.pass_ms, before.pass_ms);
        assert_eq!(controller.passes_traced(), 3);
        assert_eq!(controller.generation(), g);

        // The display in force again: nothing to show.
        controller.set_display(BRIGHTER);
        std::thread::sleep(Duration::from_millis(50));
        assert!(controller.take_frame().is_none());
        assert_eq!(controller.passes_traced(), 3);
    }

    /// With the denoiser on, a path-traced job's last frame shows its denoised image: the one
    /// `render_denoised` makes of the same settings, bit for bit, while the linear image stays
    /// the render itself. Turned off when idle, the raw image is shown again without tracing;
    /// a noiseless stage is never denoised.
    #[test]
    fn the_denoiser_shows_a_denoised_image_and_never_changes_the_film() {
        let scene = Arc::new(cornell_box());
        let controller = Controller::new(2, quiet()).unwrap();
        controller.set_denoise(true);
        let settings = small_path(40, 30, 4);
        let frame = finished(&controller, &scene, &settings);
        let (raw, denoised) = crate::transport::denoise::render_denoised(&scene, &settings);
        let denoised = denoised.unwrap();
        assert_eq!(*frame.image, raw);
        assert_eq!(frame.denoised.as_deref(), Some(&denoised));
        assert_eq!((frame.denoise, frame.denoised_samples), (true, 4));
        assert_eq!(frame.rgba, denoised.to_rgba8());
        let passes = controller.passes_traced();

        controller.set_denoise(false);
        let off = next_frame(&controller);
        assert!(!off.denoise);
        assert_eq!(off.rgba, raw.to_rgba8());
        assert_eq!(controller.passes_traced(), passes);

        // The lab's stage has no noise: nothing is denoised.
        controller.set_denoise(true);
        let _ = next_frame(&controller);
        let g = controller.submit(&scene, &small(40, 30, 2)).unwrap();
        let lab = last_frame(&controller, g);
        assert!(lab.denoised.is_none());
        assert_eq!(lab.rgba, lab.image.to_rgba8());
    }

    /// Where the features are traced apart (here the lab's stage through a lens), a job that
    /// only moves the light keeps them (traced once, the denoised image still bit for bit
    /// `render_denoised`'s of the new settings); moving the camera traces them again. The
    /// path tracer records them as it traces: it never traces them apart.
    #[test]
    fn moving_the_light_keeps_the_denoisers_features() {
        let scene = Arc::new(cornell_box());
        let controller = Controller::new(2, quiet()).unwrap();
        controller.set_denoise(true);
        let mut settings = small(40, 30, 3);
        settings.shading = crate::Shading::for_stage(crate::Stage::Shadows);
        settings.camera.aperture = 0.05;
        let _ = finished(&controller, &scene, &settings);
        assert_eq!(controller.features_traced(), 1);

        settings.light.position.x += 0.3;
        let relit = finished(&controller, &scene, &settings);
        assert_eq!(controller.features_traced(), 1);
        let (_, denoised) = crate::transport::denoise::render_denoised(&scene, &settings);
        assert_eq!(relit.denoised.as_deref(), denoised.as_ref());

        settings.camera.position.x += 0.1;
        let moved = finished(&controller, &scene, &settings);
        assert_eq!(controller.features_traced(), 2);
        let (_, denoised) = crate::transport::denoise::render_denoised(&scene, &settings);
        assert_eq!(moved.denoised.as_deref(), denoised.as_ref());

        let mut path = small_path(40, 30, 3);
        for _ in 0..2 {
            let frame = finished(&controller, &scene, &path);
            let (_, denoised) = crate::transport::denoise::render_denoised(&scene, &path);
            assert_eq!(frame.denoised.as_deref(), denoised.as_ref());
            path.camera.position.x += 0.1;
        }
        assert_eq!(
            controller.features_traced(),
            2,
            "none traced for the path tracer"
        );
        // Past the samples a film records features of, the denoised image uses the first ones.
        let long = small_path(12, 8, crate::transport::film::FEATURE_SAMPLES_RECORDED + 6);
        let frame = finished(&controller, &scene, &long);
        let (_, denoised) = crate::transport::denoise::render_denoised(&scene, &long);
        assert_eq!(frame.denoised.as_deref(), denoised.as_ref());
    }

    /// With the denoiser on, a frame that doubles the samples (2, 4, 8, 16) shows the image
    /// denoised from exactly those samples: each is `render_denoised`'s image of that many
    /// samples, bit for bit. Every frame is kept for the test to take, so none is missed.
    #[test]
    fn each_doubling_of_the_samples_is_shown_denoised() {
        let scene = Arc::new(cornell_box());
        let controller = Controller::new(2, quiet()).unwrap();
        controller.set_denoise(true);
        controller.keep_every_frame();
        let mut settings = small_path(96, 64, 20);
        let generation = controller.submit(&scene, &settings).unwrap();
        let frames = every_frame(&controller, generation);
        let doublings: Vec<&Frame> = frames
            .iter()
            .filter(|f| !f.is_preview && [2, 4, 8, 16].contains(&f.samples))
            .collect();
        let samples: Vec<u32> = doublings.iter().map(|f| f.samples).collect();
        assert_eq!(samples, [2, 4, 8, 16], "{} frames", frames.len());
        for frame in doublings {
            assert_eq!(frame.denoised_samples, frame.samples);
            settings.samples_per_pixel = frame.samples;
            let (_, denoised) = crate::transport::denoise::render_denoised(&scene, &settings);
            assert_eq!(
                frame.denoised.as_deref(),
                denoised.as_ref(),
                "{} samples",
                frame.samples
            );
        }
    }

    /// Turned on after a noisy job finished with the denoiser off, the denoiser denoises its
    /// last frame then, without tracing again.
    #[test]
    fn turning_the_denoiser_on_when_idle_denoises_the_last_frame() {
        let scene = Arc::new(cornell_box());
        let controller = Controller::new(2, quiet()).unwrap();
        let settings = small_path(40, 30, 3);
        let before = finished(&controller, &scene, &settings);
        assert!(before.denoised.is_none());
        let passes = controller.passes_traced();
        controller.set_denoise(true);
        let after = next_frame(&controller);
        let (_, denoised) = crate::transport::denoise::render_denoised(&scene, &settings);
        assert_eq!(after.denoised.as_deref(), denoised.as_ref());
        assert_eq!(after.rgba, denoised.unwrap().to_rgba8());
        assert!(Arc::ptr_eq(&after.image, &before.image));
        assert_eq!(controller.passes_traced(), passes);
    }

    /// `RAYON_NUM_THREADS` gives the default thread count up to four a core; beyond it, or
    /// unreadable, it is not used as it stands, and a note says so. An explicit count is
    /// taken up to [`MAX_THREADS`].
    #[test]
    fn the_thread_count_from_the_environment_is_capped() {
        assert_eq!(threads_from(None, 2), (2, None));
        assert_eq!(threads_from(Some("3"), 2), (3, None));
        assert_eq!(threads_from(Some("0"), 2), (2, None));
        assert_eq!(threads_from(Some("8"), 2), (8, None));
        let (n, note) = threads_from(Some("2000"), 2);
        assert_eq!(n, 8);
        assert_eq!(
            note.unwrap(),
            "RAYON_NUM_THREADS=2000 is more than 4 threads a core: using 8 (2 cores)"
        );
        let (n, note) = threads_from(Some("9"), 1);
        assert_eq!(n, 4);
        assert_eq!(
            note.unwrap(),
            "RAYON_NUM_THREADS=9 is more than 4 threads a core: using 4 (1 core)"
        );
        let (n, note) = threads_from(Some("lots"), 4);
        assert_eq!(n, 4);
        assert!(note.unwrap().contains("\"lots\" is not a number"));
        assert_eq!(threads_from(Some("99999999999999999999999"), 2).0, 8);
        assert_eq!(threads_from(Some("5000"), 300).0, MAX_THREADS);
        assert_eq!(threads_from(None, 5000).0, MAX_THREADS);
        assert_eq!(resolve_threads(100_000), MAX_THREADS);
        assert_eq!(resolve_threads(100), 100);
    }

    #[test]
    fn a_display_change_while_accumulating_does_not_restart() {
        let scene = Arc::new(cornell_box());
        let controller = Controller::new(2, quiet()).unwrap();
        let settings = small(128, 128, 200);
        let g = controller.submit(&scene, &settings).unwrap();
        // Into its accumulation, a few samples in.
        let at_change = loop {
            let frame = next_frame(&controller);
            if frame.samples >= 3 {
                break frame;
            }
        };
        assert!(!at_change.is_final(), "the job finished before the change");
        let srgb = Display {
            transform: DisplayTransform::Srgb,
            exposure: 0.5,
        };
        controller.set_display(srgb);
        // Counted after the change: passes finished between the frame above and the change
        // (a busy machine may let several by) are not the change's delay.
        let passes = controller.passes_traced();

        let mut frames = vec![at_change];
        while !frames.last().unwrap().is_final() {
            frames.push(next_frame(&controller));
        }
        // One job throughout, its samples only growing: never back to a preview or to 1.
        assert!(frames.iter().all(|f| f.generation == g && !f.is_preview));
        assert!(frames.windows(2).all(|w| w[0].samples <= w[1].samples));
        assert_eq!(controller.abandoned_jobs(), 0);
        assert_eq!(controller.passes_traced(), 201, "a preview and 200 passes");
        // The change showed after the pass under way then (the preview counts as a pass, so
        // `passes` passes make `passes − 1` samples; the pass under way when they were
        // counted adds one), not up to 40 ms of passes later.
        let first = frames.iter().find(|f| f.display == srgb).unwrap();
        assert!(
            first.samples <= passes as u32 + 1,
            "{} {passes}",
            first.samples
        );
        let last = frames.last().unwrap();
        assert_eq!((last.samples, last.display), (200, srgb));
        assert_eq!(last.rgba, srgb.to_rgba8(&last.image.pixels));
    }

    #[test]
    fn a_submission_after_a_display_change_renders_with_it() {
        let scene = Arc::new(cornell_box());
        let controller = Controller::new(2, quiet()).unwrap();
        // Nothing rendered yet: nothing to publish again, but the display is kept.
        let filmic = Display {
            transform: DisplayTransform::Filmic,
            exposure: -0.5,
        };
        controller.set_display(filmic);
        std::thread::sleep(Duration::from_millis(50));
        assert!(controller.take_frame().is_none());
        assert_eq!(controller.passes_traced(), 0);

        let settings = small(40, 30, 2);
        let g = controller.submit(&scene, &settings).unwrap();
        let frame = last_frame(&controller, g);
        assert_eq!(frame.display, filmic);
        assert_eq!(frame.rgba, filmic.to_rgba8(&frame.image.pixels));
        // The linear image is the same as with any display.
        assert_eq!(*frame.image, render(&scene, &settings));

        // A change, then at once a new job: the job shows the new display.
        controller.set_display(BRIGHTER);
        let other = small(40, 30, 1);
        let g = controller.submit(&scene, &other).unwrap();
        let frame = last_frame(&controller, g);
        assert_eq!((frame.generation, frame.display), (g, BRIGHTER));
        assert_eq!(frame.rgba, BRIGHTER.to_rgba8(&frame.image.pixels));
        assert!(controller.wait_idle(TIMEOUT));
        std::thread::sleep(Duration::from_millis(50));
        assert!(controller.take_frame().is_none(), "no stale frame after it");
    }

    #[test]
    fn a_job_that_panics_is_reported_and_the_next_one_renders() {
        let scene = Arc::new(cornell_box());
        let controller = Controller::new(2, quiet()).unwrap();
        let failing = small(40, 30, 3);
        controller.inject_panic_on_next_pass();
        let g = controller.submit(&scene, &failing).unwrap();
        // A job that panicked counts as finished: nothing more will come of it.
        assert!(controller.wait_idle(TIMEOUT));
        let error = controller.take_error().expect("the panic is reported");
        assert_eq!(
            error.message,
            format!(
                "The render panicked: {INJECTED_PANIC} (settings: scene cornell, stage lab \
                 (shadows on, indirect on), 40×30, camera (0, 0, -3.001) yaw 0° pitch 0° f 40 \
                 px, light (0, -0.5, -0.7) 14 W, 3 spp, seed 0)"
            )
        );
        assert_eq!(error.settings.as_ref(), Some(&failing));
        let json = error.settings_json().unwrap();
        assert_eq!(
            serde_json::from_str::<RenderSettings>(&json).unwrap(),
            failing
        );
        assert!(controller.take_error().is_none(), "reported once");
        // Its first pass panicked (40 < 64: no preview): nothing traced, nothing published.
        assert!(controller.take_frame().is_none());
        assert_eq!(controller.passes_traced(), 0);
        assert_eq!(controller.generation(), g);

        // The worker goes on: the next job renders as if nothing had happened.
        let next = small(48, 32, 4);
        let g = controller.submit(&scene, &next).unwrap();
        let frame = last_frame(&controller, g);
        assert_eq!(frame.settings, next);
        assert_eq!(*frame.image, render(&scene, &next));
        assert!(controller.take_error().is_none());
    }

    #[test]
    fn after_a_panic_mid_job_nothing_more_of_it_is_shown() {
        let scene = Arc::new(cornell_box());
        let controller = Controller::new(2, quiet()).unwrap();
        // Long enough to be mid-accumulation when the panic comes.
        let settings = small(128, 128, 4096);
        let g = controller.submit(&scene, &settings).unwrap();
        while next_frame(&controller).samples < 2 {}
        controller.inject_panic_on_next_pass();
        assert!(controller.wait_idle(TIMEOUT));
        let error = controller.take_error().expect("the panic is reported");
        assert!(error.message.contains(INJECTED_PANIC), "{}", error.message);
        // The frame the worker may have published before the panic is gone from the slot, and a
        // display change does not show the failed job's last frame again.
        assert!(controller.take_frame().is_none());
        controller.set_display(BRIGHTER);
        std::thread::sleep(Duration::from_millis(50));
        assert!(controller.take_frame().is_none());
        assert_eq!(controller.abandoned_jobs(), 0);
        assert_eq!(controller.generation(), g);
    }

    #[test]
    fn a_panic_message_is_read_from_its_payload() {
        assert_eq!(catch_panic(|| 7), Ok(7));
        assert_eq!(
            catch_panic(|| panic!("at {}", 3)),
            Err::<(), _>("at 3".to_owned())
        );
        assert_eq!(
            catch_panic(|| panic!("static")),
            Err::<(), _>("static".to_owned())
        );
        let other = catch_panic(|| std::panic::panic_any(42));
        assert_eq!(other, Err::<(), _>("a panic with no message".to_owned()));
    }

    #[test]
    fn frames_come_less_often_as_a_job_goes_on() {
        let ms = Duration::from_millis;
        assert_eq!(frame_interval(ms(0)), MIN_FRAME_INTERVAL);
        assert_eq!(frame_interval(ms(400)), MIN_FRAME_INTERVAL);
        assert_eq!(frame_interval(ms(1000)), ms(100));
        assert_eq!(frame_interval(ms(2500)), MAX_FRAME_INTERVAL);
        assert_eq!(
            frame_interval(Duration::from_secs(3600)),
            MAX_FRAME_INTERVAL
        );
    }

    #[test]
    fn preview_sizes() {
        assert_eq!(preview_size(1024, 768), Some((128, 96)));
        assert_eq!(preview_size(512, 4), Some((64, 1)));
        assert_eq!(preview_size(32, 32), None);
    }
}
