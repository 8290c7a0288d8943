//! The writers' way to the file: a buffer, and (on Linux) the disk's write-back of each
//! stretch written started at once, so that the disk writes while the rest is encoded and
//! the final sync waits for little more than the last stretch instead of the whole file.

use std::fs::File;
use std::io::{self, BufWriter, Write};

/// Capacity of the [`BufWriter`] between a writer closure and the file.
const FILE_BUFFER: usize = 1 << 20;

/// Bytes written between two requests to start the write-back.
const WRITEBACK: u64 = 8 << 20;

/// Writes what `write` gives to `file`, then syncs it to the disk.
pub(super) fn write_and_sync<F>(file: File, write: F) -> io::Result<()>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let mut out = BufWriter::with_capacity(FILE_BUFFER, Writeback::new(file));
    write(&mut out)?;
    let file = out.into_inner().map_err(|e| e.into_error())?.file;
    file.sync_all()
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

    /// The bytes written in pieces of every size arrive in order, across write-back requests.
    #[test]
    fn bytes_arrive_in_order() {
        let n = 2 * WRITEBACK as usize + 12345;
        let data: Vec<u8> = (0..n).map(|i| (i * 7 % 251) as u8).collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out");
        write_and_sync(File::create(&path).unwrap(), |w| {
            let mut rest = &data[..];
            let mut k = 1;
            while !rest.is_empty() {
                let m = k.min(rest.len());
                w.write_all(&rest[..m])?;
                rest = &rest[m..];
                k = k * 3 + 1;
            }
            w.flush()
        })
        .unwrap();
        let mut back = Vec::new();
        File::open(&path).unwrap().read_to_end(&mut back).unwrap();
        assert!(back == data);
    }
}
