//! A pool of planning sessions: at most N jobs at once (503 beyond), each on a blocking thread
//! with its own `Session`, each within the time budget (504 past it).

use crate::error::{ApiError, ErrorKind};
use skyplan_plan::{Session, World};
use std::collections::HashSet;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::Semaphore;

/// Grids, boxes and roadmaps a session may cache (distinct altitude/margin/cell sizes) before it
/// is replaced by a fresh one, so that varied requests cannot grow memory without bound.
const MAX_CACHED_SHAPES: usize = 8;

/// A session and the cache keys it has seen.
struct Worker {
    session: Session,
    shapes: HashSet<[u64; 4]>,
}

impl Worker {
    fn new(world: &World) -> Self {
        Self {
            session: Session::new(world.clone()),
            shapes: HashSet::new(),
        }
    }
}

/// N sessions behind a semaphore of N permits.
pub(crate) struct Pool {
    world: World,
    permits: Arc<Semaphore>,
    idle: Mutex<Vec<Worker>>,
    budget: Duration,
    size: usize,
}

impl Pool {
    pub(crate) fn new(world: World, size: usize, budget: Duration) -> Self {
        let size = size.max(1);
        Self {
            idle: Mutex::new((0..size).map(|_| Worker::new(&world)).collect()),
            world,
            permits: Arc::new(Semaphore::new(size)),
            budget,
            size,
        }
    }

    pub(crate) fn world(&self) -> &World {
        &self.world
    }

    /// Runs `job` on an idle session on a blocking thread. `shape` identifies what the job caches
    /// (altitude, margin, cell size …). Busy: 503 at once; past the budget: 504 (the job runs
    /// on and frees its session and permit when it ends).
    pub(crate) async fn run<T, F>(self: &Arc<Self>, shape: [f64; 4], job: F) -> Result<T, ApiError>
    where
        T: Send + 'static,
        F: FnOnce(&mut Session) -> T + Send + 'static,
    {
        let Ok(permit) = Arc::clone(&self.permits).try_acquire_owned() else {
            return Err(ApiError::new(
                ErrorKind::Busy,
                format!(
                    "all {} planning workers are busy; retry in a moment",
                    self.size()
                ),
            ));
        };
        let pool = Arc::clone(self);
        // Long preprocessing gives up a little before the budget, so the client hears why (a
        // `timeout` failure) instead of a bare 504 while the work goes on in the background.
        let deadline = std::time::Instant::now() + self.budget.mul_f64(0.8);
        let handle = tokio::task::spawn_blocking(move || {
            let mut worker = pool.take();
            worker.session.set_deadline(Some(deadline));
            let out = job(&mut worker.session);
            worker.session.set_deadline(None);
            worker.shapes.insert(shape.map(f64::to_bits));
            if worker.shapes.len() > MAX_CACHED_SHAPES {
                worker = Worker::new(&pool.world);
            }
            pool.give_back(worker);
            drop(permit);
            out
        });
        match tokio::time::timeout(self.budget, handle).await {
            Ok(Ok(out)) => Ok(out),
            Ok(Err(_)) => Err(ApiError::internal(
                "the planner stopped unexpectedly (a bug); the request was not planned",
            )),
            Err(_) => Err(ApiError::new(
                ErrorKind::OverBudget,
                format!(
                    "the request took longer than the server's budget of {} ms",
                    self.budget.as_millis()
                ),
            )),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<Worker>> {
        // A panic while holding the lock cannot leave the vector half-changed (push/pop only).
        self.idle.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn take(&self) -> Worker {
        // A permit guarantees an idle worker, unless a job panicked and lost its own.
        self.lock()
            .pop()
            .unwrap_or_else(|| Worker::new(&self.world))
    }

    fn give_back(&self, worker: Worker) {
        self.lock().push(worker);
    }

    /// The number of sessions (the concurrency limit).
    pub(crate) fn size(&self) -> usize {
        self.size
    }
}
