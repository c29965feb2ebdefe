//! A pool of planning sessions behind a bounded FIFO queue: at most N jobs run at once, each on
//! a blocking thread with its own `Session`; up to `queue_depth` more wait their turn in arrival
//! order. Every request has one time budget from its arrival, queue included: a request the
//! queue has no room for, or whose expected wait (the median of the last job durations) leaves no time to
//! plan within the budget, is answered 503 at once (with `Retry-After`); one still waiting when
//! its turn could no longer finish in time is answered 504 `queue_timeout`; a job running past
//! the budget is answered 504 `over_budget`.

use crate::error::{ApiError, ErrorKind};
use serde::Serialize;
use skyplan_plan::{Session, World};
use std::collections::{HashSet, VecDeque};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::{OwnedSemaphorePermit, Semaphore};

/// Grids, boxes and roadmaps a session may cache (distinct altitude/margin/cell sizes) before it
/// is replaced by a fresh one, so that varied requests cannot grow memory without bound.
const MAX_CACHED_SHAPES: usize = 8;

/// The share of the budget a job's session may use before it gives up with a `timeout`
/// failure (so the client hears why instead of a bare 504 while the work goes on).
const SESSION_SHARE: f64 = 0.8;

/// Jobs whose median duration estimates the queue's wait (the median, so that one slow job
/// does not make the server refuse what it could serve).
const RECENT_JOBS: usize = 16;

/// Longest `Retry-After` the server suggests, seconds.
const MAX_RETRY_AFTER_S: u64 = 60;

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

/// What `GET /api/status` answers: the pool's state and its counters since the server started.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub(crate) struct PoolStatus {
    /// Planning workers (jobs run at once).
    pub workers: usize,
    /// Workers running a job now.
    pub busy: usize,
    /// Requests waiting for a worker now.
    pub queued: usize,
    /// Most requests that may wait.
    pub queue_depth: usize,
    /// The time budget of one request, queue included, milliseconds.
    pub budget_ms: u64,
    /// Median duration of the last 16 jobs, milliseconds; `None` before the first job ends.
    pub recent_job_ms: Option<u64>,
    /// Jobs a worker finished within the budget, whatever the planner answered.
    pub served: u64,
    /// Requests answered 503 at once: the queue was full or its wait would not fit the budget.
    pub rejected: u64,
    /// Requests answered 504 `queue_timeout`: still waiting when they could no longer finish.
    pub queue_timeouts: u64,
    /// Requests answered 504 `over_budget`: their job ran past the budget.
    pub over_budget: u64,
}

/// Counters since the pool was made.
#[derive(Default)]
struct Counters {
    served: AtomicU64,
    rejected: AtomicU64,
    queue_timeouts: AtomicU64,
    over_budget: AtomicU64,
    /// The durations of the last jobs, microseconds, oldest first.
    recent_jobs_us: Mutex<VecDeque<u64>>,
}

/// A place in the queue: leaving it (admitted, timed out, or the client gone) frees it.
struct InQueue<'a>(&'a AtomicUsize);

impl Drop for InQueue<'_> {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::AcqRel);
    }
}

/// N sessions behind a semaphore of N permits (tokio's semaphore serves waiters first in,
/// first out) and a bounded count of waiters.
pub(crate) struct Pool {
    world: World,
    permits: Arc<Semaphore>,
    idle: Mutex<Vec<Worker>>,
    budget: Duration,
    size: usize,
    queue_depth: usize,
    queued: AtomicUsize,
    counters: Counters,
}

impl Pool {
    pub(crate) fn new(world: World, size: usize, queue_depth: usize, budget: Duration) -> Self {
        let size = size.max(1);
        Self {
            idle: Mutex::new((0..size).map(|_| Worker::new(&world)).collect()),
            world,
            permits: Arc::new(Semaphore::new(size)),
            budget,
            size,
            queue_depth,
            queued: AtomicUsize::new(0),
            counters: Counters::default(),
        }
    }

    /// When a request that arrived at `arrived` must have its work done: the session's share
    /// of the budget (work outside the pool, such as the space-time search, keeps to it too).
    pub(crate) fn deadline_from(&self, arrived: Instant) -> Instant {
        arrived + self.budget.mul_f64(SESSION_SHARE)
    }

    pub(crate) fn world(&self) -> &World {
        &self.world
    }

    /// Runs `job` on an idle session on a blocking thread, after waiting its turn in the queue.
    /// `shape` identifies what the job caches (altitude, margin, cell size …). Queue full, or
    /// an expected wait past the budget: 503 at once; still queued when the turn could no longer
    /// finish in time: 504 `queue_timeout`; running past the budget: 504 `over_budget` (the job
    /// runs on and frees its session and permit when it ends).
    pub(crate) async fn run<T, F>(self: &Arc<Self>, shape: [f64; 4], job: F) -> Result<T, ApiError>
    where
        T: Send + 'static,
        F: FnOnce(&mut Session) -> T + Send + 'static,
    {
        let arrived = Instant::now();
        let permit = match Arc::clone(&self.permits).try_acquire_owned() {
            Ok(permit) => permit,
            Err(_) => self.wait_turn(arrived).await?,
        };
        let pool = Arc::clone(self);
        let deadline = self.deadline_from(arrived);
        let handle = tokio::task::spawn_blocking(move || {
            let started = Instant::now();
            let mut worker = pool.take();
            worker.session.set_deadline(Some(deadline));
            let out = job(&mut worker.session);
            worker.session.set_deadline(None);
            worker.shapes.insert(shape.map(f64::to_bits));
            if worker.shapes.len() > MAX_CACHED_SHAPES {
                worker = Worker::new(&pool.world);
            }
            pool.give_back(worker);
            pool.record_job(started.elapsed());
            drop(permit);
            out
        });
        let left = self.budget.saturating_sub(arrived.elapsed());
        match tokio::time::timeout(left, handle).await {
            Ok(Ok(out)) => {
                self.counters.served.fetch_add(1, Ordering::Relaxed);
                Ok(out)
            }
            Ok(Err(_)) => {
                self.counters.served.fetch_add(1, Ordering::Relaxed);
                Err(ApiError::internal(
                    "the planner stopped unexpectedly (a bug); the request was not planned",
                ))
            }
            Err(_) => {
                self.counters.over_budget.fetch_add(1, Ordering::Relaxed);
                Err(ApiError::new(
                    ErrorKind::OverBudget,
                    format!(
                        "the request took longer than the server's budget of {} ms",
                        self.budget.as_millis()
                    ),
                ))
            }
        }
    }

    /// Waits in the queue for a worker: the permit, or the 503/504 that answers the request.
    async fn wait_turn(&self, arrived: Instant) -> Result<OwnedSemaphorePermit, ApiError> {
        let recent = self.recent_job();
        let joined = self
            .queued
            .fetch_update(Ordering::AcqRel, Ordering::Acquire, |n| {
                (n < self.queue_depth).then_some(n + 1)
            });
        let Ok(ahead) = joined else {
            let ahead = self.queue_depth;
            return Err(self.reject(
                format!(
                    "all {} planning workers are busy and {} requests are queued, the most this server holds",
                    self.size, self.queue_depth
                ),
                self.drain_estimate(ahead, recent),
            ));
        };
        let place = InQueue(&self.queued);
        // The expected start: the jobs ahead, `size` at a time, each about the recent duration.
        let expected_start = self.drain_estimate(ahead + 1, recent);
        if let Some(job) = recent
            && expected_start + job > self.budget
        {
            drop(place);
            return Err(self.reject(
                format!(
                    "all {} planning workers are busy and the {} queued requests ahead would take about {} ms, \
                     leaving no time to plan within the server's budget of {} ms",
                    self.size,
                    ahead,
                    expected_start.as_millis(),
                    self.budget.as_millis()
                ),
                expected_start,
            ));
        }
        // Starting later than this leaves the job no time before the session's deadline.
        let latest_start = self
            .budget
            .mul_f64(SESSION_SHARE)
            .saturating_sub(recent.unwrap_or(Duration::ZERO));
        let wait = latest_start.saturating_sub(arrived.elapsed());
        match tokio::time::timeout(wait, Arc::clone(&self.permits).acquire_owned()).await {
            Ok(Ok(permit)) => Ok(permit),
            Ok(Err(_)) => Err(ApiError::internal(
                "the planning workers were shut down (a bug); the request was not planned",
            )),
            Err(_) => {
                self.counters.queue_timeouts.fetch_add(1, Ordering::Relaxed);
                Err(ApiError::new(
                    ErrorKind::QueueTimeout,
                    format!(
                        "timed out while queued: waited {} ms for one of {} busy planning workers; \
                         a later start could not finish within the server's budget of {} ms",
                        arrived.elapsed().as_millis(),
                        self.size,
                        self.budget.as_millis()
                    ),
                ))
            }
        }
    }

    /// A 503 `busy` with a `Retry-After` of about `wait` (1 s to a minute).
    fn reject(&self, message: String, wait: Duration) -> ApiError {
        self.counters.rejected.fetch_add(1, Ordering::Relaxed);
        let retry_after_s = wait
            .as_secs_f64()
            .ceil()
            .clamp(1.0, MAX_RETRY_AFTER_S as f64) as u64;
        ApiError::new(ErrorKind::Busy, message).with_retry_after(retry_after_s)
    }

    /// About how long `jobs` jobs take on the pool's workers, from the recent job duration
    /// (zero before any job has ended).
    fn drain_estimate(&self, jobs: usize, recent: Option<Duration>) -> Duration {
        let rounds = jobs.div_ceil(self.size);
        recent.map_or(Duration::ZERO, |job| {
            job.saturating_mul(u32::try_from(rounds).unwrap_or(u32::MAX))
        })
    }

    fn recent(&self) -> std::sync::MutexGuard<'_, VecDeque<u64>> {
        // Push/pop only: a panic cannot leave the list half-changed.
        (self.counters.recent_jobs_us.lock()).unwrap_or_else(|e| e.into_inner())
    }

    /// The median duration of the last jobs, once a job has ended.
    fn recent_job(&self) -> Option<Duration> {
        let mut us: Vec<u64> = self.recent().iter().copied().collect();
        us.sort_unstable();
        us.get(us.len() / 2).map(|&m| Duration::from_micros(m))
    }

    /// Keeps a job's duration among the last [`RECENT_JOBS`].
    fn record_job(&self, took: Duration) {
        let us = u64::try_from(took.as_micros()).unwrap_or(u64::MAX);
        let mut recent = self.recent();
        if recent.len() == RECENT_JOBS {
            recent.pop_front();
        }
        recent.push_back(us);
    }

    /// The pool's state and counters.
    pub(crate) fn status(&self) -> PoolStatus {
        let c = &self.counters;
        PoolStatus {
            workers: self.size,
            busy: self.size.saturating_sub(self.permits.available_permits()),
            queued: self.queued.load(Ordering::Acquire),
            queue_depth: self.queue_depth,
            budget_ms: u64::try_from(self.budget.as_millis()).unwrap_or(u64::MAX),
            recent_job_ms: self
                .recent_job()
                .map(|d| u64::try_from(d.as_millis()).unwrap_or(u64::MAX)),
            served: c.served.load(Ordering::Relaxed),
            rejected: c.rejected.load(Ordering::Relaxed),
            queue_timeouts: c.queue_timeouts.load(Ordering::Relaxed),
            over_budget: c.over_budget.load(Ordering::Relaxed),
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use axum::response::IntoResponse;
    use std::sync::mpsc;

    fn pool(workers: usize, queue_depth: usize, budget: Duration) -> Arc<Pool> {
        let grid = skyplan_cspace::Grid2::from_ascii("....\n....").expect("a grid");
        Arc::new(Pool::new(
            World::from_grid("tiny", grid),
            workers,
            queue_depth,
            budget,
        ))
    }

    /// Yields until `done` holds of the pool's status (the spawned requests run meanwhile).
    async fn until(pool: &Pool, done: impl Fn(&PoolStatus) -> bool) {
        while !done(&pool.status()) {
            tokio::task::yield_now().await;
        }
    }

    /// A request whose job holds its worker until the returned sender sends (or is dropped).
    fn blocked(
        pool: &Arc<Pool>,
    ) -> (
        mpsc::Sender<()>,
        tokio::task::JoinHandle<Result<u8, ApiError>>,
    ) {
        let (release, wait) = mpsc::channel::<()>();
        let pool = Arc::clone(pool);
        let task = tokio::spawn(async move {
            pool.run([0.0; 4], move |_| {
                let _ = wait.recv();
                1
            })
            .await
        });
        (release, task)
    }

    fn quick(pool: &Arc<Pool>, n: u8) -> tokio::task::JoinHandle<Result<u8, ApiError>> {
        let pool = Arc::clone(pool);
        tokio::spawn(async move { pool.run([0.0; 4], move |_| n).await })
    }

    #[tokio::test]
    async fn a_full_queue_answers_503_with_retry_after_and_the_queued_request_waits_its_turn() {
        let pool = pool(1, 1, Duration::from_secs(600));
        let (release, first) = blocked(&pool);
        until(&pool, |s| s.busy == 1).await;
        let second = quick(&pool, 2);
        until(&pool, |s| s.queued == 1).await;
        let third = pool.run([0.0; 4], |_| 3u8).await;
        let err = third.expect_err("no room in the queue");
        assert_eq!(err.kind, ErrorKind::Busy);
        assert!(
            err.message.contains("1 requests are queued"),
            "{}",
            err.message
        );
        let response = err.into_response();
        assert_eq!(
            response.status(),
            axum::http::StatusCode::SERVICE_UNAVAILABLE
        );
        assert_eq!(response.headers()["retry-after"], "1");
        release.send(()).expect("the blocked job waits");
        assert_eq!(first.await.expect("joins"), Ok(1));
        assert_eq!(second.await.expect("joins"), Ok(2));
        until(&pool, |s| s.busy == 0).await;
        let s = pool.status();
        assert_eq!((s.workers, s.busy, s.queued, s.queue_depth), (1, 0, 0, 1));
        assert_eq!(
            (s.served, s.rejected, s.queue_timeouts, s.over_budget),
            (2, 1, 0, 0)
        );
        assert!(s.recent_job_ms.is_some());
    }

    #[tokio::test]
    async fn a_request_queued_past_its_budget_gets_504_queue_timeout() {
        let pool = pool(1, 4, Duration::from_millis(100));
        let (release, first) = blocked(&pool);
        until(&pool, |s| s.busy == 1).await;
        // The worker stays blocked until the queued request has its answer.
        let err = pool
            .run([0.0; 4], |_| 2u8)
            .await
            .expect_err("never gets a worker");
        assert_eq!(err.kind, ErrorKind::QueueTimeout);
        assert_eq!(err.kind.status(), axum::http::StatusCode::GATEWAY_TIMEOUT);
        assert!(
            err.message.contains("timed out while queued"),
            "{}",
            err.message
        );
        assert_eq!(
            first.await.expect("joins").map_err(|e| e.kind),
            Err(ErrorKind::OverBudget)
        );
        release.send(()).expect("the blocked job waits");
        until(&pool, |s| s.busy == 0).await;
        assert_eq!(pool.run([0.0; 4], |_| 3u8).await, Ok(3));
        let s = pool.status();
        assert_eq!((s.busy, s.queued), (0, 0));
        assert_eq!(
            (s.served, s.rejected, s.queue_timeouts, s.over_budget),
            (1, 0, 1, 1)
        );
    }

    #[tokio::test]
    async fn a_wait_that_would_leave_no_time_to_plan_is_refused_at_once() {
        let pool = pool(1, 8, Duration::from_secs(10));
        // Recent jobs took 6 s: one ahead plus one's own is 12 s, past the 10 s budget.
        pool.record_job(Duration::from_secs(6));
        let (release, first) = blocked(&pool);
        until(&pool, |s| s.busy == 1).await;
        let err = pool.run([0.0; 4], |_| 2u8).await.expect_err("refused");
        assert_eq!(err.kind, ErrorKind::Busy);
        assert!(
            err.message.contains("leaving no time to plan"),
            "{}",
            err.message
        );
        assert_eq!(err.retry_after_s, Some(6));
        release.send(()).expect("the blocked job waits");
        assert_eq!(first.await.expect("joins"), Ok(1));
        let s = pool.status();
        assert_eq!((s.served, s.rejected, s.queued), (1, 1, 0));
    }

    #[tokio::test]
    async fn without_a_queue_a_busy_pool_answers_503_at_once() {
        let pool = pool(1, 0, Duration::from_secs(600));
        let (release, first) = blocked(&pool);
        until(&pool, |s| s.busy == 1).await;
        let err = pool.run([0.0; 4], |_| 2u8).await.expect_err("refused");
        assert_eq!(err.kind, ErrorKind::Busy);
        release.send(()).expect("the blocked job waits");
        assert_eq!(first.await.expect("joins"), Ok(1));
        assert_eq!(pool.run([0.0; 4], |_| 3u8).await, Ok(3));
    }
}
