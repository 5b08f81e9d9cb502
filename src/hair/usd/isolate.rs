//! Reading a USD stage in a child process. The `openusd` crate trusts the sizes a crate file
//! declares: a corrupt count makes it allocate exabytes and abort the process, which would take an
//! artist's unsaved edits with it. On Unix the stage is therefore read in a forked child with a
//! memory limit and a deadline; what it read comes back through a pipe in a small binary form
//! ([`Wire`]), and a child that dies or overruns is a clear error. Elsewhere it is read in process.

use std::time::Duration;

/// A value that crosses the pipe: written by the child, read back with every length checked
/// against the bytes that arrived.
pub trait Wire: Sized {
    fn put(&self, out: &mut Vec<u8>);
    fn get(input: &mut &[u8]) -> Option<Self>;
}

/// Limits for one read: memory beyond what the process already maps, and time.
pub struct Limits {
    pub extra_memory: u64,
    pub deadline: Duration,
}

/// Runs `read` in a child process and returns its result, or why the child failed.
#[cfg(unix)]
pub fn in_child<T: Wire>(
    limits: &Limits,
    read: impl FnOnce() -> Result<T, String>,
) -> Result<T, String> {
    let mut fds = [0i32; 2];
    // Close-on-exec: a process the parent starts meanwhile must not hold the write end open, or
    // the parent would wait for an end of file that never comes.
    // SAFETY: pipe2 writes two descriptors into the array it is given.
    if unsafe { libc::pipe2(fds.as_mut_ptr(), libc::O_CLOEXEC) } != 0 {
        return Err(format!(
            "cannot start the USD reader: {}",
            std::io::Error::last_os_error()
        ));
    }
    let (rx, tx) = (fds[0], fds[1]);
    // SAFETY: the child only runs the reader, writes to its pipe and leaves with _exit; it takes
    // no lock another thread of the parent could hold but the allocator's, which glibc resets in
    // the child.
    let pid = unsafe { libc::fork() };
    if pid < 0 {
        // SAFETY: closing the descriptors this function opened.
        unsafe {
            libc::close(rx);
            libc::close(tx);
        }
        return Err(format!(
            "cannot start the USD reader: {}",
            std::io::Error::last_os_error()
        ));
    }
    if pid == 0 {
        // SAFETY: in the child; nothing here returns into the parent's code.
        unsafe {
            libc::close(rx);
            limit_memory(limits.extra_memory);
            // The allocator's abort message would land in the user's terminal: the parent
            // reports the failure instead.
            let null = libc::open(c"/dev/null".as_ptr(), libc::O_WRONLY);
            if null >= 0 {
                libc::dup2(null, 2);
                libc::close(null);
            }
        }
        std::panic::set_hook(Box::new(|_| {}));
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(read))
            .unwrap_or_else(|_| Err("the USD reader failed on malformed data".into()));
        let mut bytes = Vec::new();
        result.put(&mut bytes);
        let mut rest = &bytes[..];
        while !rest.is_empty() {
            // SAFETY: writing from a live buffer to the pipe this child owns.
            let n = unsafe { libc::write(tx, rest.as_ptr().cast(), rest.len()) };
            if n <= 0 {
                break;
            }
            rest = &rest[n as usize..];
        }
        // SAFETY: leaving the child without running the parent's exit handlers.
        unsafe { libc::_exit(0) };
    }
    // SAFETY: the parent keeps only the read end.
    unsafe { libc::close(tx) };
    let received = receive(rx, pid, limits.deadline);
    // SAFETY: closing the read end and reaping the child, which has exited or been killed.
    let status = unsafe {
        libc::close(rx);
        let mut status = 0;
        while libc::waitpid(pid, &mut status, 0) < 0
            && std::io::Error::last_os_error().kind() == std::io::ErrorKind::Interrupted
        {}
        status
    };
    let bytes = received?;
    if !libc::WIFEXITED(status) || libc::WEXITSTATUS(status) != 0 {
        return Err(
            "the USD reader crashed on this file (malformed data, or more memory than it may use)"
                .into(),
        );
    }
    let mut input = &bytes[..];
    Result::<T, String>::get(&mut input).ok_or("the USD reader's answer was cut short")?
}

#[cfg(not(unix))]
pub fn in_child<T: Wire>(
    _limits: &Limits,
    read: impl FnOnce() -> Result<T, String>,
) -> Result<T, String> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(read))
        .unwrap_or_else(|_| Err("the USD reader failed on malformed data".into()))
}

/// Caps the child's address space at what it maps now plus `extra` bytes, so a runaway
/// allocation fails at once instead of exhausting the machine.
#[cfg(unix)]
unsafe fn limit_memory(extra: u64) {
    // SAFETY: sysconf only reads a system constant.
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) }.max(4096) as u64;
    let mapped = std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .map(|pages| pages * page);
    let mut current = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: reading this process's own limit into a valid struct.
    let known = unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut current) } == 0;
    if let (Some(mapped), true) = (mapped, known) {
        // A soft limit above the hard one would be refused: stay under it.
        let want = mapped.saturating_add(extra).min(current.rlim_max);
        let limit = libc::rlimit {
            rlim_cur: want,
            rlim_max: current.rlim_max,
        };
        // SAFETY: setting this process's own limit from a valid struct.
        unsafe { libc::setrlimit(libc::RLIMIT_AS, &limit) };
    }
}

/// Everything the child writes, or an error when it is silent past the deadline (it is killed).
#[cfg(unix)]
fn receive(rx: i32, pid: i32, deadline: Duration) -> Result<Vec<u8>, String> {
    let start = std::time::Instant::now();
    let mut bytes = Vec::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let left = deadline.saturating_sub(start.elapsed());
        let mut poll = libc::pollfd {
            fd: rx,
            events: libc::POLLIN,
            revents: 0,
        };
        let ms = left.as_millis().min(i32::MAX as u128) as i32;
        // SAFETY: polling one valid descriptor.
        let ready = unsafe { libc::poll(&mut poll, 1, ms) };
        if ready == 0 || left.is_zero() {
            // SAFETY: killing the child this function started.
            unsafe { libc::kill(pid, libc::SIGKILL) };
            return Err(format!(
                "the USD reader took longer than {} s and was stopped",
                deadline.as_secs()
            ));
        }
        if ready < 0 {
            if std::io::Error::last_os_error().kind() == std::io::ErrorKind::Interrupted {
                continue;
            }
            // SAFETY: as above.
            unsafe { libc::kill(pid, libc::SIGKILL) };
            return Err("the USD reader's pipe failed".into());
        }
        // SAFETY: reading into a live buffer of the given length.
        let n = unsafe { libc::read(rx, buf.as_mut_ptr().cast(), buf.len()) };
        match n {
            0 => return Ok(bytes),
            n if n > 0 => bytes.extend_from_slice(&buf[..n as usize]),
            _ if std::io::Error::last_os_error().kind() == std::io::ErrorKind::Interrupted => {}
            _ => return Err("the USD reader's pipe failed".into()),
        }
    }
}

impl Wire for u64 {
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
    fn get(input: &mut &[u8]) -> Option<Self> {
        let (head, rest) = input.split_first_chunk::<8>()?;
        *input = rest;
        Some(u64::from_le_bytes(*head))
    }
}

impl Wire for u8 {
    fn put(&self, out: &mut Vec<u8>) {
        out.push(*self);
    }
    fn get(input: &mut &[u8]) -> Option<Self> {
        let (head, rest) = input.split_first()?;
        *input = rest;
        Some(*head)
    }
}

impl Wire for f64 {
    fn put(&self, out: &mut Vec<u8>) {
        self.to_bits().put(out);
    }
    fn get(input: &mut &[u8]) -> Option<Self> {
        u64::get(input).map(f64::from_bits)
    }
}

impl Wire for String {
    fn put(&self, out: &mut Vec<u8>) {
        (self.len() as u64).put(out);
        out.extend_from_slice(self.as_bytes());
    }
    fn get(input: &mut &[u8]) -> Option<Self> {
        let n = usize::try_from(u64::get(input)?).ok()?;
        let bytes = input.get(..n)?;
        *input = &input[n..];
        String::from_utf8(bytes.to_vec()).ok()
    }
}

impl<T: Wire> Wire for Option<T> {
    fn put(&self, out: &mut Vec<u8>) {
        match self {
            None => 0u8.put(out),
            Some(v) => {
                1u8.put(out);
                v.put(out);
            }
        }
    }
    fn get(input: &mut &[u8]) -> Option<Self> {
        match u8::get(input)? {
            0 => Some(None),
            1 => Some(Some(T::get(input)?)),
            _ => None,
        }
    }
}

impl<T: Wire, E: Wire> Wire for Result<T, E> {
    fn put(&self, out: &mut Vec<u8>) {
        match self {
            Ok(v) => {
                0u8.put(out);
                v.put(out);
            }
            Err(e) => {
                1u8.put(out);
                e.put(out);
            }
        }
    }
    fn get(input: &mut &[u8]) -> Option<Self> {
        match u8::get(input)? {
            0 => Some(Ok(T::get(input)?)),
            1 => Some(Err(E::get(input)?)),
            _ => None,
        }
    }
}

/// Plain numbers in bulk: a count, then the little-endian bytes.
pub fn put_pods<T: bytemuck::Pod>(v: &[T], out: &mut Vec<u8>) {
    (v.len() as u64).put(out);
    out.extend_from_slice(bytemuck::cast_slice(v));
}

pub fn get_pods<T: bytemuck::Pod>(input: &mut &[u8]) -> Option<Vec<T>> {
    let n = usize::try_from(u64::get(input)?).ok()?;
    let bytes = n.checked_mul(size_of::<T>())?;
    let slice = input.get(..bytes)?;
    *input = &input[bytes..];
    Some(bytemuck::pod_collect_to_vec(slice))
}

impl<T: Wire> Wire for Vec<T> {
    fn put(&self, out: &mut Vec<u8>) {
        (self.len() as u64).put(out);
        for v in self {
            v.put(out);
        }
    }
    fn get(input: &mut &[u8]) -> Option<Self> {
        let n = usize::try_from(u64::get(input)?).ok()?;
        // Every element takes at least one byte: a count beyond the bytes left is corrupt.
        if n > input.len() {
            return None;
        }
        (0..n).map(|_| T::get(input)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_cross_and_cut_answers_are_refused() {
        let v: Result<Vec<Option<String>>, String> = Ok(vec![Some("a".into()), None]);
        let mut bytes = Vec::new();
        v.put(&mut bytes);
        let mut input = &bytes[..];
        assert_eq!(Result::get(&mut input), Some(v));
        let mut cut = &bytes[..bytes.len() - 1];
        assert_eq!(Result::<Vec<Option<String>>, String>::get(&mut cut), None);
        let mut huge = Vec::new();
        u64::MAX.put(&mut huge);
        assert_eq!(get_pods::<f32>(&mut &huge[..]), None);
    }

    #[cfg(unix)]
    #[test]
    fn a_child_that_aborts_or_hangs_is_an_error() {
        let limits = Limits {
            extra_memory: 1 << 30,
            deadline: Duration::from_secs(2),
        };
        let ok = in_child(&limits, || Ok(String::from("read")));
        assert_eq!(ok, Ok("read".into()));
        let huge = in_child(&limits, || {
            let v = std::hint::black_box(vec![1u8; 1 << 40]);
            Ok(format!("{}", v[12345]))
        });
        assert!(huge.unwrap_err().contains("crashed"));
        let slow = Limits {
            deadline: Duration::from_millis(200),
            ..limits
        };
        let hang = in_child(&slow, || {
            std::thread::sleep(Duration::from_secs(30));
            Ok(String::new())
        });
        assert!(hang.unwrap_err().contains("longer than"));
    }
}
