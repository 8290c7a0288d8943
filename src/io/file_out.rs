//! The writers' way to the file: with more than one worker thread, the bytes go to the file
//! on a thread of their own, so that formatting and encoding go on while the system copies
//! them; and (on Linux) the disk's write-back of each stretch written starts at once, so the
//! final sync waits for little more than the last stretch instead of the whole file.
//!
//! Memory stays bounded: at most [`DEPTH`] blocks of [`BLOCK`] bytes wait for the thread.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};

/// Bytes handed to the writing thread at a time.
const BLOCK: usize = 1 << 20;

/// Blocks waiting for the writing thread at most.
const DEPTH: usize = 4;

/// Bytes written between two requests to start the write-back.
const WRITEBACK: u64 = 8 << 20;

/// Writes what `write` gives to `file` (on a thread of its own when the current rayon pool
/// has more than one thread), then syncs it to the disk.
pub(super) fn write_and_sync<F>(file: File, write: F) -> io::Result<()>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let file = if rayon::current_num_threads() > 1 {
        threaded(file, write)?
    } else {
        let mut out = BufWriter::with_capacity(BLOCK, Writeback::new(file));
        write(&mut out)?;
        out.into_inner().map_err(|e| e.into_error())?.file
    };
    file.sync_all()
}

/// Runs `write` here and the file writes on a scoped thread; returns the file once all is
/// written. An error of the file comes before the one it caused here.
fn threaded<F>(file: File, write: F) -> io::Result<File>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let (tx, rx) = sync_channel::<Vec<u8>>(DEPTH);
    std::thread::scope(|s| {
        let writer = s.spawn(move || drain(rx, Writeback::new(file)));
        let mut out = Blocks {
            tx,
            buf: Vec::with_capacity(BLOCK),
        };
        let here = write(&mut out).and_then(|()| out.send());
        drop(out);
        let there = writer
            .join()
            .unwrap_or_else(|p| std::panic::resume_unwind(p));
        match (here, there) {
            (_, Err(e)) | (Err(e), Ok(_)) => Err(e),
            (Ok(()), Ok(file)) => Ok(file),
        }
    })
}

/// Writes the blocks received to `out` until the sender is dropped.
fn drain(rx: Receiver<Vec<u8>>, mut out: Writeback) -> io::Result<File> {
    for block in rx {
        out.write_all(&block)?;
    }
    Ok(out.file)
}

/// A [`Write`] that collects bytes into blocks and sends them to the writing thread.
struct Blocks {
    tx: SyncSender<Vec<u8>>,
    buf: Vec<u8>,
}

impl Blocks {
    /// Sends the bytes collected so far.
    fn send(&mut self) -> io::Result<()> {
        if self.buf.is_empty() {
            return Ok(());
        }
        let block = std::mem::replace(&mut self.buf, Vec::with_capacity(BLOCK));
        self.tx
            .send(block)
            .map_err(|_| io::Error::other("the file's writing thread stopped"))
    }
}

impl Write for Blocks {
    fn write(&mut self, data: &[u8]) -> io::Result<usize> {
        let take = (BLOCK - self.buf.len()).min(data.len());
        self.buf.extend_from_slice(&data[..take]);
        if self.buf.len() == BLOCK {
            self.send()?;
        }
        Ok(take)
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// A file that asks the system to start writing back every [`WRITEBACK`] bytes written.
struct Writeback {
    file: File,
    written: u64,
    synced: u64,
}

impl Writeback {
    fn new(file: File) -> Self {
        Writeback {
            file,
            written: 0,
            synced: 0,
        }
    }

    /// Starts the write-back of what was written since the last time (a hint: the final
    /// sync reports any error).
    fn start_writeback(&mut self) {
        #[cfg(target_os = "linux")]
        {
            use std::os::fd::AsRawFd;
            let (from, len) = (self.synced as i64, (self.written - self.synced) as i64);
            // SAFETY: a plain system call on a file descriptor this struct owns.
            unsafe {
                libc::sync_file_range(
                    self.file.as_raw_fd(),
                    from,
                    len,
                    libc::SYNC_FILE_RANGE_WRITE,
                );
            }
        }
        self.synced = self.written;
    }
}

impl Write for Writeback {
    fn write(&mut self, data: &[u8]) -> io::Result<usize> {
        let n = self.file.write(data)?;
        self.written += n as u64;
        if self.written - self.synced >= WRITEBACK {
            self.start_writeback();
        }
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.file.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;

    /// The bytes written in pieces of every size arrive in order, one thread or several.
    #[test]
    fn bytes_arrive_in_order() {
        let data: Vec<u8> = (0..3 * BLOCK + 12345)
            .map(|i| (i * 7 % 251) as u8)
            .collect();
        for threads in [1, 2] {
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join("out");
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                write_and_sync(File::create(&path).unwrap(), |w| {
                    let mut rest = &data[..];
                    let mut n = 1;
                    while !rest.is_empty() {
                        let k = n.min(rest.len());
                        w.write_all(&rest[..k])?;
                        rest = &rest[k..];
                        n = n * 3 + 1;
                    }
                    w.flush()
                })
            })
            .unwrap();
            let mut back = Vec::new();
            File::open(&path).unwrap().read_to_end(&mut back).unwrap();
            assert!(back == data, "{threads} threads");
        }
    }

    /// An error of the writer closure is returned, with the writing thread stopped.
    #[test]
    fn a_writer_error_is_returned() {
        let dir = tempfile::tempdir().unwrap();
        let file = File::create(dir.path().join("out")).unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let e = pool
            .install(|| {
                write_and_sync(file, |w| {
                    w.write_all(&[1; 3 * BLOCK])?;
                    Err(io::Error::other("stop"))
                })
            })
            .unwrap_err();
        assert_eq!(e.to_string(), "stop");
    }
}
