//! Worker threads: how many a run may ask for, and pools that never panic.
//!
//! Thousands of threads buy nothing on any machine we know of and exhaust the process's
//! address space or task limit first, so a request is bounded ([`MAX_THREADS`]); where the
//! operating system still refuses (a container's task limit, `ulimit -v`), [`check`] reports
//! its error before a run starts, and [`pool`] makes do with the threads it is granted (every
//! result is bit for bit the same on any number of threads).

/// The most worker threads a run may ask for.
pub const MAX_THREADS: usize = 1024;

/// Why a thread count is refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ThreadsError {
    #[error("must be at least 1 (leave it out for one per core)")]
    Zero,
    #[error("{0} is more than the {MAX_THREADS} worker threads a run may use")]
    TooMany(usize),
    /// The operating system would not start them (its error).
    #[error("cannot start {threads} worker threads: {reason}")]
    Refused { threads: usize, reason: String },
}

/// Checks a requested thread count (`None`: one per core): between 1 and [`MAX_THREADS`], and
/// granted by the operating system now (a pool of that many is started and stopped).
pub fn check(threads: Option<usize>) -> Result<Option<usize>, ThreadsError> {
    let Some(n) = threads else {
        return Ok(None);
    };
    if n == 0 {
        return Err(ThreadsError::Zero);
    }
    if n > MAX_THREADS {
        return Err(ThreadsError::TooMany(n));
    }
    if let Some(room) = address_space_room()
        && address_space_needed(n) > room
    {
        let fit = (1..n)
            .rev()
            .find(|&k| address_space_needed(k) <= room)
            .unwrap_or(0);
        return Err(ThreadsError::Refused {
            threads: n,
            reason: format!(
                "the address-space limit (ulimit -v) leaves room for about {fit} (each reserves \
                 its stack, and up to eight per core an arena of the C allocator); ask for fewer"
            ),
        });
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map_err(|e| ThreadsError::Refused {
            threads: n,
            reason: e.to_string(),
        })?;
    Ok(threads)
}

/// The address space `n` worker threads take, to judge a count against `ulimit -v` before
/// starting any: each its stack (std's 2 MiB) with its signal stack and guard pages, and up to
/// eight per core an arena of the C allocator (glibc reserves 64 MiB each). A thread started
/// where its stack fits but its signal stack does not aborts the process (the standard
/// library cannot report that), so a count that does not fit is refused before any starts.
fn address_space_needed(n: usize) -> u64 {
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
    let arenas = n.min(8 * cores) as u64;
    (n as u64)
        .saturating_mul((2 << 20) + (128 << 10))
        .saturating_add(arenas.saturating_mul(64 << 20))
}

/// Room left under the address-space limit (`RLIMIT_AS`) besides what is mapped now, where
/// there is a limit (Linux; `None` elsewhere or where it cannot be read).
fn address_space_room() -> Option<u64> {
    #[cfg(target_os = "linux")]
    {
        let mut r = libc::rlimit {
            rlim_cur: 0,
            rlim_max: 0,
        };
        // SAFETY: getrlimit writes the struct it is given.
        if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut r) } != 0
            || r.rlim_cur == libc::RLIM_INFINITY
        {
            return None;
        }
        let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
        let pages: u64 = statm.split_whitespace().next()?.parse().ok()?;
        // SAFETY: sysconf reads a constant.
        let page = u64::try_from(unsafe { libc::sysconf(libc::_SC_PAGESIZE) }).ok()?;
        Some(r.rlim_cur.saturating_sub(pages.saturating_mul(page)))
    }
    #[cfg(not(target_os = "linux"))]
    {
        None
    }
}

/// A pool of `threads` workers (`None`: rayon's default, one per core) or, where the
/// operating system refuses that many, of as many as it grants (halving the count; at the
/// last, the calling thread alone). Results do not depend on the count.
pub fn pool(threads: Option<usize>) -> rayon::ThreadPool {
    let build = |n: usize| rayon::ThreadPoolBuilder::new().num_threads(n).build();
    if let Ok(pool) = build(threads.unwrap_or(0).min(MAX_THREADS)) {
        return pool;
    }
    let cores = || std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut n = threads.unwrap_or_else(cores).min(MAX_THREADS);
    while n > 1 {
        n /= 2;
        if let Ok(pool) = build(n) {
            return pool;
        }
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .use_current_thread()
        .build()
        .expect("a pool of the calling thread starts no thread")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_outside_one_to_the_bound_are_refused_and_others_granted() {
        assert_eq!(check(None), Ok(None));
        assert_eq!(check(Some(0)), Err(ThreadsError::Zero));
        assert_eq!(
            check(Some(MAX_THREADS + 1)),
            Err(ThreadsError::TooMany(MAX_THREADS + 1))
        );
        assert_eq!(
            check(Some(usize::MAX)),
            Err(ThreadsError::TooMany(usize::MAX))
        );
        assert_eq!(check(Some(3)), Ok(Some(3)));
        assert_eq!(pool(Some(3)).current_num_threads(), 3);
    }

    #[test]
    fn the_last_resort_pool_runs_spawned_work_on_the_calling_thread() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .use_current_thread()
            .build()
            .unwrap();
        let sum = std::sync::atomic::AtomicUsize::new(0);
        pool.install(|| {
            rayon::scope(|s| {
                for i in 0..10 {
                    let sum = &sum;
                    s.spawn(move |_| {
                        sum.fetch_add(i, std::sync::atomic::Ordering::Relaxed);
                    });
                }
            })
        });
        assert_eq!(sum.into_inner(), 45);
    }
}
