//! Board interfaces the core offers beside the ESC: non-volatile
//! parameter storage here, the firmware image store with the bootloader
//! ([`crate::firmware::ImageStore`]). Device hardware (a power stage, I/O
//! drivers) belongs to the device's own crate.

/// Errors of non-volatile storage.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum NvError {
    /// The access runs past the end of the storage.
    #[error("access {offset}+{len} past the end of the {capacity}-byte storage")]
    OutOfRange {
        /// First byte.
        offset: usize,
        /// Length.
        len: usize,
        /// Storage size.
        capacity: usize,
    },
    /// The device lost power (simulation) or the medium failed.
    #[error("storage write interrupted")]
    Interrupted,
}

/// Byte-addressed non-volatile storage (EEPROM, flash page, file).
///
/// A write may be cut by a power loss after any byte; the parameter store
/// ([`crate::params`]) is built so that this never leaves a mixed set.
pub trait NvStorage {
    /// Size in bytes.
    fn capacity(&self) -> usize;
    /// Reads `buf.len()` bytes at `offset`.
    fn read(&self, offset: usize, buf: &mut [u8]) -> Result<(), NvError>;
    /// Writes `data` at `offset`.
    fn write(&mut self, offset: usize, data: &[u8]) -> Result<(), NvError>;
    /// Completed writes so far (lets a host notice a change cheaply; 0 when
    /// the storage does not count).
    fn write_count(&self) -> u32 {
        0
    }
}

/// RAM-backed storage that survives simulated power cycles of the device
/// (the object is kept) and can simulate a power cut after N bytes.
#[derive(Debug, Clone)]
pub struct MemNv<const N: usize> {
    bytes: [u8; N],
    /// Bytes still written before the simulated power cut, if armed.
    cut_after: Option<usize>,
    writes: u32,
}

impl<const N: usize> Default for MemNv<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> MemNv<N> {
    /// Erased storage (all 0xFF).
    pub const fn new() -> Self {
        MemNv {
            bytes: [0xFF; N],
            cut_after: None,
            writes: 0,
        }
    }

    /// Arms a power cut: only `bytes` more bytes reach the medium, later
    /// writes fail with [`NvError::Interrupted`].
    pub fn cut_power_after(&mut self, bytes: usize) {
        self.cut_after = Some(bytes);
    }

    /// Restores power (disarms the cut).
    pub fn restore_power(&mut self) {
        self.cut_after = None;
    }

    /// The raw contents.
    pub fn bytes(&self) -> &[u8; N] {
        &self.bytes
    }

    /// Raw contents, mutably (to corrupt them in tests).
    pub fn bytes_mut(&mut self) -> &mut [u8; N] {
        &mut self.bytes
    }

    /// Number of write calls (flash wear accounting).
    pub fn write_count(&self) -> u32 {
        self.writes
    }
}

impl<const N: usize> NvStorage for MemNv<N> {
    fn capacity(&self) -> usize {
        N
    }

    fn write_count(&self) -> u32 {
        self.writes
    }

    fn read(&self, offset: usize, buf: &mut [u8]) -> Result<(), NvError> {
        let src = offset
            .checked_add(buf.len())
            .and_then(|end| self.bytes.get(offset..end))
            .ok_or(NvError::OutOfRange {
                offset,
                len: buf.len(),
                capacity: N,
            })?;
        buf.copy_from_slice(src);
        Ok(())
    }

    fn write(&mut self, offset: usize, data: &[u8]) -> Result<(), NvError> {
        let end =
            offset
                .checked_add(data.len())
                .filter(|e| *e <= N)
                .ok_or(NvError::OutOfRange {
                    offset,
                    len: data.len(),
                    capacity: N,
                })?;
        self.writes = self.writes.saturating_add(1);
        let allowed = self.cut_after.map_or(data.len(), |c| c.min(data.len()));
        if let (Some(dst), Some(src)) = (
            self.bytes.get_mut(offset..offset + allowed),
            data.get(..allowed),
        ) {
            dst.copy_from_slice(src);
        }
        let _ = end;
        if let Some(c) = self.cut_after.as_mut() {
            *c -= allowed;
            if allowed < data.len() {
                return Err(NvError::Interrupted);
            }
        }
        Ok(())
    }
}
