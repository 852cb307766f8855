//! Durable host state of one software slave: its parameter storage (the
//! EEPROM behind SAVE) in a directory, written so that a power cut at any
//! instant leaves the old or the new parameter set, never neither.
//!
//! * The storage is kept in regions of [`REGION`] bytes (one parameter slot
//!   each, see [`ecat_slave::params`]), **one file per region**
//!   (`params-0.bin`, `params-1.bin`). A SAVE changes one slot, so only one
//!   file is rewritten and no single write can destroy both copies.
//! * A region is written to a new file, `sync_all`ed, renamed over the old
//!   one, and the directory is `fsync`ed: after [`SlaveState::persist`]
//!   returns, the data is on stable storage. The runner persists after the
//!   firmware step that executed a SAVE and before it reads the next frame,
//!   so the master cannot see the acknowledgement (0x11111111, or the SDO
//!   download response) before the data is durable.
//! * The first persist writes every region and then a stamp file
//!   (`params.stamp`). Once the stamp exists, a missing, short or
//!   unreadable region file is damage, not a new device: the region is
//!   loaded as zeros, which the parameter store reports as an EEPROM data
//!   error (power stage off, MEMORY = 1) unless the other slot is valid.
//!   Only a directory without stamp and regions is a blank (new) device.

use ecat_slave::hal::NvStorage;
use std::fs::{self, File, OpenOptions};
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};

/// Bytes per region file: one parameter slot.
pub const REGION: usize = ecat_slave::params::SLOT_SIZE;

const STAMP: &str = "params.stamp";
/// The single-file layout of earlier versions, still read.
const LEGACY: &str = "params.bin";

/// What [`SlaveState::load`] found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Loaded {
    /// Nothing stored yet: a new device.
    Blank,
    /// Every region restored.
    Restored,
    /// These regions were missing, short or unreadable after the storage
    /// had been written: loaded as zeros (an EEPROM data error unless the
    /// other slot is valid).
    Damaged(Vec<usize>),
}

/// The parameter storage of one slave in `dir`.
#[derive(Debug)]
pub struct SlaveState {
    dir: PathBuf,
    /// What is on disk, region by region (`None`: not written yet).
    on_disk: Vec<Option<Vec<u8>>>,
    stamped: bool,
    last_count: Option<u32>,
}

fn region_path(dir: &Path, k: usize) -> PathBuf {
    dir.join(format!("params-{k}.bin"))
}

/// `fsync` of a directory, so a rename or a new file in it is durable.
pub fn sync_dir(dir: &Path) -> io::Result<()> {
    File::open(dir)?.sync_all()
}

/// Writes `bytes` to `dir/name` durably: a new file, `sync_all`, rename
/// over the old one, `fsync` of the directory.
pub fn write_durably(dir: &Path, name: &str, bytes: &[u8]) -> io::Result<()> {
    let tmp = dir.join(format!("{name}.tmp"));
    {
        let mut f = OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(true)
            .open(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
    }
    fs::rename(&tmp, dir.join(name))?;
    sync_dir(dir)
}

fn read_exact_file(path: &Path, len: usize) -> Option<Vec<u8>> {
    let mut f = File::open(path).ok()?;
    let mut buf = Vec::with_capacity(len + 1);
    f.read_to_end(&mut buf).ok()?;
    (buf.len() == len).then_some(buf)
}

impl SlaveState {
    /// The state in `dir` (created if needed).
    pub fn open(dir: impl AsRef<Path>) -> io::Result<Self> {
        let dir = dir.as_ref().to_path_buf();
        fs::create_dir_all(&dir)?;
        let stamped = dir.join(STAMP).exists();
        Ok(SlaveState {
            dir,
            on_disk: Vec::new(),
            stamped,
            last_count: None,
        })
    }

    /// The directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    fn regions(nv: &dyn NvStorage) -> usize {
        nv.capacity().div_ceil(REGION)
    }

    fn region_len(nv: &dyn NvStorage, k: usize) -> usize {
        REGION.min(nv.capacity().saturating_sub(k * REGION))
    }

    /// Loads the stored regions into `nv` (which should be erased, 0xFF).
    pub fn load(&mut self, nv: &mut dyn NvStorage) -> io::Result<Loaded> {
        let n = Self::regions(nv);
        self.on_disk = vec![None; n];
        let any_region = (0..n).any(|k| region_path(&self.dir, k).exists());
        if !self.stamped && !any_region {
            // An older runner kept everything in one file: loaded, and
            // rewritten in regions at the next persist.
            return match fs::read(self.dir.join(LEGACY)) {
                Ok(bytes) => {
                    let len = bytes.len().min(nv.capacity());
                    nv.write(0, bytes.get(..len).unwrap_or(&[]))
                        .map_err(|e| io::Error::other(e.to_string()))?;
                    self.last_count = None;
                    Ok(Loaded::Restored)
                }
                Err(e) if e.kind() == io::ErrorKind::NotFound => {
                    self.last_count = Some(nv.write_count());
                    Ok(Loaded::Blank)
                }
                Err(e) => Err(e),
            };
        }
        let mut damaged = Vec::new();
        for k in 0..n {
            let len = Self::region_len(nv, k);
            let path = region_path(&self.dir, k);
            let bytes = match read_exact_file(&path, len) {
                Some(b) => b,
                // Before the stamp, a region that never got written is
                // simply erased.
                None if !self.stamped && !path.exists() => continue,
                None => {
                    damaged.push(k);
                    vec![0u8; len]
                }
            };
            nv.write(k * REGION, &bytes)
                .map_err(|e| io::Error::other(e.to_string()))?;
            if let Some(slot) = self.on_disk.get_mut(k) {
                *slot = Some(bytes);
            }
        }
        // Leftovers of an interrupted write are never used.
        for k in 0..n {
            let _ = fs::remove_file(self.dir.join(format!("params-{k}.bin.tmp")));
        }
        self.last_count = Some(nv.write_count());
        Ok(if damaged.is_empty() {
            Loaded::Restored
        } else {
            Loaded::Damaged(damaged)
        })
    }

    /// Writes every region of `nv` that differs from what is on disk,
    /// durably (see the module docs). Returns how many regions were
    /// written; cheap when nothing changed (the storage's write count).
    pub fn persist(&mut self, nv: &dyn NvStorage) -> io::Result<usize> {
        let count = nv.write_count();
        if self.last_count == Some(count) {
            return Ok(0);
        }
        let n = Self::regions(nv);
        self.on_disk.resize(n, None);
        let mut written = 0;
        for k in 0..n {
            let mut bytes = vec![0u8; Self::region_len(nv, k)];
            nv.read(k * REGION, &mut bytes)
                .map_err(|e| io::Error::other(e.to_string()))?;
            // The first persist writes every region, so that the stamp
            // means "all regions exist".
            let known = self.on_disk.get(k).and_then(Option::as_deref);
            if self.stamped && known == Some(&bytes[..]) {
                continue;
            }
            write_durably(&self.dir, &format!("params-{k}.bin"), &bytes)?;
            if let Some(slot) = self.on_disk.get_mut(k) {
                *slot = Some(bytes);
            }
            written += 1;
        }
        if !self.stamped {
            write_durably(&self.dir, STAMP, b"params written\n")?;
            self.stamped = true;
            let _ = fs::remove_file(self.dir.join(LEGACY));
        }
        self.last_count = Some(count);
        Ok(written)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::indexing_slicing)]
mod tests {
    use super::*;
    use ecat_slave::hal::MemNv;

    fn temp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("ecat-state-dir-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        d
    }

    #[test]
    fn a_new_directory_is_blank_and_the_first_persist_writes_every_region_and_the_stamp() {
        let dir = temp("new");
        let mut s = SlaveState::open(&dir).unwrap();
        let mut nv = MemNv::<1024>::new();
        assert_eq!(s.load(&mut nv).unwrap(), Loaded::Blank);
        nv.write(3, &[1, 2, 3]).unwrap();
        assert_eq!(s.persist(&nv).unwrap(), 2);
        assert!(dir.join(STAMP).exists());
        assert_eq!(s.persist(&nv).unwrap(), 0, "nothing changed");
        // A SAVE to slot 1 rewrites only its file.
        nv.write(REGION + 5, &[9]).unwrap();
        let before = fs::metadata(region_path(&dir, 0))
            .unwrap()
            .modified()
            .unwrap();
        assert_eq!(s.persist(&nv).unwrap(), 1);
        assert_eq!(
            fs::metadata(region_path(&dir, 0))
                .unwrap()
                .modified()
                .unwrap(),
            before
        );
        let mut back = MemNv::<1024>::new();
        assert_eq!(
            SlaveState::open(&dir).unwrap().load(&mut back).unwrap(),
            Loaded::Restored
        );
        let (mut a, mut b) = ([0u8; 1024], [0u8; 1024]);
        nv.read(0, &mut a).unwrap();
        back.read(0, &mut b).unwrap();
        assert_eq!(a, b);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_empty_or_missing_region_after_the_stamp_is_damage_not_a_new_device() {
        let dir = temp("damage");
        let mut s = SlaveState::open(&dir).unwrap();
        let mut nv = MemNv::<1024>::new();
        s.load(&mut nv).unwrap();
        nv.write(0, &[7; 16]).unwrap();
        s.persist(&nv).unwrap();
        // What a power cut leaves on some file systems: an empty file.
        File::create(region_path(&dir, 0)).unwrap();
        let mut back = MemNv::<1024>::new();
        assert_eq!(
            SlaveState::open(&dir).unwrap().load(&mut back).unwrap(),
            Loaded::Damaged(vec![0])
        );
        let mut head = [0xFFu8; 4];
        back.read(0, &mut head).unwrap();
        assert_eq!(
            head, [0; 4],
            "zeros, not erased: the store reports corruption"
        );
        fs::remove_file(region_path(&dir, 1)).unwrap();
        let mut back = MemNv::<1024>::new();
        assert_eq!(
            SlaveState::open(&dir).unwrap().load(&mut back).unwrap(),
            Loaded::Damaged(vec![0, 1])
        );
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_single_file_layout_of_earlier_versions_is_read_and_replaced() {
        let dir = temp("legacy");
        fs::create_dir_all(&dir).unwrap();
        let mut old = vec![0xFFu8; 1024];
        old[..4].copy_from_slice(b"PRM1");
        fs::write(dir.join(LEGACY), &old).unwrap();
        let mut s = SlaveState::open(&dir).unwrap();
        let mut nv = MemNv::<1024>::new();
        assert_eq!(s.load(&mut nv).unwrap(), Loaded::Restored);
        let mut head = [0u8; 4];
        nv.read(0, &mut head).unwrap();
        assert_eq!(&head, b"PRM1");
        s.persist(&nv).unwrap();
        assert!(!dir.join(LEGACY).exists());
        assert!(region_path(&dir, 0).exists() && region_path(&dir, 1).exists());
        fs::remove_dir_all(&dir).unwrap();
    }
}
