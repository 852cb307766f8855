//! A file-backed [`ImageStore`] for the host (soft slave): a directory with
//! `slot_a.bin`, `slot_b.bin` and the two boot-state copies `state_0.bin`,
//! `state_1.bin`. Host only (`std` feature).
//!
//! Durability follows what the boot logic relies on, at the lowest cost
//! per FoE chunk: erasing a slot truncates its file (no 2 MiB of 0xFF to
//! write); chunk writes go to the page cache without a sync; writing a
//! boot-state record first syncs every slot written since the last
//! record, then writes and syncs the record (and the directory when a
//! file was created). A record therefore never points at image data that
//! is not on stable storage, and a download costs one sync at its end
//! instead of one per chunk.

use std::fs::{self, File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use ecat_slave::firmware::{BootState, ImageStore, STATE_RECORD_LEN, Slot, StoreError};

/// An [`ImageStore`] in a directory. Slots read as `0xFF` beyond the end of
/// their file (erased flash); writes overwrite.
#[derive(Debug, Clone)]
pub struct FileStore {
    dir: PathBuf,
    capacity: usize,
    /// Slot A written since the last sync.
    dirty_a: bool,
    /// Slot B written since the last sync.
    dirty_b: bool,
}

fn io<T>(r: std::io::Result<T>) -> Result<T, StoreError> {
    r.map_err(|_| StoreError::Io)
}

impl FileStore {
    /// Opens (creating if needed) the store in `dir`, with slots of
    /// `capacity` bytes.
    pub fn open(dir: impl AsRef<Path>, capacity: usize) -> std::io::Result<Self> {
        fs::create_dir_all(dir.as_ref())?;
        Ok(Self {
            dir: dir.as_ref().to_path_buf(),
            capacity,
            dirty_a: false,
            dirty_b: false,
        })
    }

    /// Whether anything was ever written here (a slot or a boot record):
    /// a store that has been written and has no readable boot record lost
    /// it, it is not new.
    pub fn has_been_written(&self) -> bool {
        [Slot::A, Slot::B]
            .iter()
            .map(|s| self.slot_path(*s))
            .chain([self.state_path(0), self.state_path(1)])
            .any(|p| p.exists())
    }

    fn dirty(&mut self, slot: Slot) -> &mut bool {
        match slot {
            Slot::A => &mut self.dirty_a,
            Slot::B => &mut self.dirty_b,
        }
    }

    fn sync_dirty(&mut self) -> Result<(), StoreError> {
        for slot in [Slot::A, Slot::B] {
            if *self.dirty(slot) {
                io(io(File::open(self.slot_path(slot)))?.sync_data())?;
                *self.dirty(slot) = false;
            }
        }
        Ok(())
    }

    fn sync_dir(&self) -> Result<(), StoreError> {
        io(io(File::open(&self.dir))?.sync_all())
    }

    /// The directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Path of a slot file.
    pub fn slot_path(&self, slot: Slot) -> PathBuf {
        self.dir.join(match slot {
            Slot::A => "slot_a.bin",
            Slot::B => "slot_b.bin",
        })
    }

    /// Path of boot-state copy 0 or 1.
    pub fn state_path(&self, copy: usize) -> PathBuf {
        self.dir.join(if copy == 0 {
            "state_0.bin"
        } else {
            "state_1.bin"
        })
    }

    /// Boot-state copy `copy`: a missing file reads as blank (no record),
    /// a file that cannot be opened or read is [`StoreError::Io`], not a
    /// blank record (see [`power_on`](ecat_slave::firmware::power_on)).
    fn read_copy(&self, copy: usize) -> Result<[u8; STATE_RECORD_LEN], StoreError> {
        let mut buf = [0u8; STATE_RECORD_LEN];
        let mut f = match File::open(self.state_path(copy)) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(buf),
            Err(_) => return Err(StoreError::Io),
        };
        // A short file is a torn record (it fails its CRC).
        let mut filled = 0;
        while let Some(rest) = buf.get_mut(filled..).filter(|r| !r.is_empty()) {
            match f.read(rest) {
                Ok(0) => break,
                Ok(n) => filled += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(_) => return Err(StoreError::Io),
            }
        }
        Ok(buf)
    }

    fn check(&self, offset: usize, len: usize) -> Result<(), StoreError> {
        match offset.checked_add(len) {
            Some(end) if end <= self.capacity => Ok(()),
            _ => Err(StoreError::OutOfBounds),
        }
    }
}

impl ImageStore for FileStore {
    fn slot_capacity(&self) -> usize {
        self.capacity
    }

    fn erase(&mut self, slot: Slot) -> Result<(), StoreError> {
        // An empty file reads as erased flash (0xFF) to its capacity.
        let created = !self.slot_path(slot).exists();
        io(File::create(self.slot_path(slot)))?;
        *self.dirty(slot) = true;
        if created {
            self.sync_dir()?;
        }
        Ok(())
    }

    fn write(&mut self, slot: Slot, offset: usize, data: &[u8]) -> Result<(), StoreError> {
        self.check(offset, data.len())?;
        let created = !self.slot_path(slot).exists();
        let mut f = io(OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(false)
            .open(self.slot_path(slot)))?;
        // Erased flash between the end of the file and `offset`.
        let len = io(f.metadata())?.len();
        if len < offset as u64 {
            io(f.seek(SeekFrom::Start(len)))?;
            let gap = offset - len as usize;
            io(f.write_all(&vec![0xFF; gap]))?;
        }
        io(f.seek(SeekFrom::Start(offset as u64)))?;
        io(f.write_all(data))?;
        *self.dirty(slot) = true;
        if created {
            self.sync_dir()?;
        }
        Ok(())
    }

    fn read(&self, slot: Slot, offset: usize, buf: &mut [u8]) -> Result<usize, StoreError> {
        if offset > self.capacity {
            return Err(StoreError::OutOfBounds);
        }
        let n = buf.len().min(self.capacity - offset);
        let dst = buf.get_mut(..n).ok_or(StoreError::OutOfBounds)?;
        dst.fill(0xFF);
        if let Ok(mut f) = File::open(self.slot_path(slot)) {
            io(f.seek(SeekFrom::Start(offset as u64)))?;
            let mut filled = 0;
            while filled < n {
                let got = io(f.read(dst.get_mut(filled..).unwrap_or(&mut [])))?;
                if got == 0 {
                    break;
                }
                filled += got;
            }
        }
        Ok(n)
    }

    fn read_state(&self) -> Result<BootState, StoreError> {
        let (a, b) = (self.read_copy(0)?, self.read_copy(1)?);
        BootState::read_bank([&a, &b])
            .map(|(_, s)| s)
            .ok_or(StoreError::NoState)
    }

    fn write_state(&mut self, state: &BootState) -> Result<(), StoreError> {
        // The image data a record may point at is durable first.
        self.sync_dirty()?;
        let (a, b) = (self.read_copy(0)?, self.read_copy(1)?);
        let (copy, record) = BootState::bank_write([&a, &b], state);
        let created = !self.state_path(copy).exists();
        let mut f = io(OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(false)
            .open(self.state_path(copy)))?;
        io(f.write_all(&record))?;
        io(f.sync_all())?;
        if created {
            self.sync_dir()?;
        }
        Ok(())
    }
}

#[cfg(test)]
#[allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]
mod tests {
    use super::*;
    use ecat_slave::firmware::{
        BootOutcome, DeviceIdentity, EFW_HEADER_LEN, EfwHeaderRepr, EfwValidator, FirmwareVersion,
        begin_download, commit_pending, confirm_boot, finish_download, pack, power_on, provision,
        write_chunk,
    };

    fn temp_dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("ecat-file-store-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        dir
    }

    #[test]
    fn file_store_reads_erased_bytes_and_round_trips_writes() {
        let dir = temp_dir("rw");
        let mut s = FileStore::open(&dir, 100).unwrap();
        let mut buf = [0u8; 8];
        assert_eq!(s.read(Slot::B, 96, &mut buf), Ok(4));
        assert_eq!(&buf[..4], &[0xFF; 4]);
        s.erase(Slot::B).unwrap();
        s.write(Slot::B, 10, b"hello").unwrap();
        assert_eq!(s.read(Slot::B, 8, &mut buf), Ok(8));
        assert_eq!(&buf, b"\xFF\xFFhello\xFF");
        assert_eq!(s.write(Slot::B, 98, b"abc"), Err(StoreError::OutOfBounds));
        assert_eq!(s.read_state(), Err(StoreError::NoState));
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn file_store_survives_reopen_and_runs_an_update() {
        let dir = temp_dir("update");
        let device = DeviceIdentity {
            vendor_id: 1,
            product_code: 2,
            revision: 3,
        };
        {
            let mut s = FileStore::open(&dir, 4096).unwrap();
            provision(&mut s, FirmwareVersion::new("1.0").unwrap(), &[1; 1000]).unwrap();
        }
        let header = EfwHeaderRepr {
            header_len: EFW_HEADER_LEN as u16,
            flags: 0,
            vendor_id: 1,
            product_code: 2,
            revision_min: 3,
            revision_max: 3,
            version: FirmwareVersion::new("2.0").unwrap(),
            payload_len: 0,
            payload_crc: 0,
        };
        let mut img = vec![0u8; EFW_HEADER_LEN + 3000];
        pack(&header, &[7; 3000], &mut img).unwrap();
        {
            let mut s = FileStore::open(&dir, 4096).unwrap();
            let slot = begin_download(&mut s).unwrap();
            assert_eq!(slot, Slot::B);
            let mut v = EfwValidator::new(device, s.slot_capacity());
            for c in img.chunks(500) {
                let off = v.payload_received();
                let p = v.feed(c).unwrap();
                write_chunk(&mut s, slot, off, p).unwrap();
            }
            finish_download(&mut s, slot, &v.finish().unwrap()).unwrap();
            commit_pending(&mut s).unwrap();
        }
        let mut s = FileStore::open(&dir, 4096).unwrap();
        let d = power_on(&mut s);
        assert_eq!(d.outcome, BootOutcome::Trial { attempt: 1 });
        assert_eq!((d.slot, d.version.as_str()), (Some(Slot::B), "2.0"));
        confirm_boot(&mut s).unwrap();
        let s = FileStore::open(&dir, 4096).unwrap();
        assert_eq!(s.read_state().unwrap().active, Slot::B);
        assert!(s.state_path(0).exists() && s.state_path(1).exists());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn torn_state_file_falls_back_to_the_other_copy() {
        let dir = temp_dir("torn");
        let mut s = FileStore::open(&dir, 64).unwrap();
        provision(&mut s, FirmwareVersion::new("1.0").unwrap(), &[1; 10]).unwrap();
        provision(&mut s, FirmwareVersion::new("1.1").unwrap(), &[2; 10]).unwrap();
        // the newer copy (state_1) is torn by a power cut
        let mut f = OpenOptions::new()
            .write(true)
            .open(s.state_path(1))
            .unwrap();
        f.write_all(&[0u8; 20]).unwrap();
        drop(f);
        assert_eq!(s.read_state().unwrap().active_image.version.as_str(), "1.0");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_boot_record_that_cannot_be_read_is_an_io_error_and_starts_nothing() {
        let dir = temp_dir("unreadable");
        let mut s = FileStore::open(&dir, 64).unwrap();
        provision(&mut s, FirmwareVersion::new("1.0").unwrap(), &[1; 10]).unwrap();
        provision(&mut s, FirmwareVersion::new("1.1").unwrap(), &[2; 10]).unwrap();
        // The newer copy cannot be read (a directory: open works, read
        // fails, also for root); it is not a blank store.
        fs::remove_file(s.state_path(1)).unwrap();
        fs::create_dir(s.state_path(1)).unwrap();
        assert_eq!(s.read_state(), Err(StoreError::Io));
        assert_eq!(power_on(&mut s).slot, None);
        fs::remove_dir_all(&dir).unwrap();
    }
}
