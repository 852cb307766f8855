//! The line of twins an ENI describes.
//!
//! Each ENI slave is matched by vendor ID, product code and revision: first
//! against the built-in devices (real firmware on the core, given by the
//! caller), then against the devices of an [`EsiLibrary`] (exact revision
//! first, else the highest revision of that product, which is reported).
//! A slave nothing matches is an error listing every such slave: nothing
//! starts on a partial line.

use std::path::{Path, PathBuf};

use ecat_sim::chain::LineSlave;

use crate::eni::EniSlave;
use crate::esi::{EsiDevice, EsiFile};
use crate::{InputRules, TwinError, load_esi, twin_with_modules};

/// The ESI files a line takes its devices from.
#[derive(Debug, Default)]
pub struct EsiLibrary {
    files: Vec<(PathBuf, EsiFile)>,
}

impl EsiLibrary {
    /// Every `*.xml` file of `dir` (not recursive); a file that is not a
    /// valid ESI is an error (naming the file, element and line).
    pub fn load_dir(dir: &Path) -> Result<Self, TwinError> {
        let io = |source| TwinError::Io {
            path: dir.display().to_string(),
            source,
        };
        let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(io)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("xml")))
            .collect();
        paths.sort();
        let mut lib = EsiLibrary::default();
        for p in paths {
            let f = load_esi(&p)?;
            lib.files.push((p, f));
        }
        Ok(lib)
    }

    /// Adds one parsed file.
    pub fn add(&mut self, path: PathBuf, file: EsiFile) {
        self.files.push((path, file));
    }

    /// Number of devices over every file.
    pub fn device_count(&self) -> usize {
        self.files.iter().map(|(_, f)| f.devices.len()).sum()
    }

    /// The device with this identity: exact revision, else the highest
    /// revision of the product (`exact` false).
    pub fn find(
        &self,
        vendor_id: u32,
        product_code: u32,
        revision: u32,
    ) -> Option<(&Path, &EsiDevice, bool)> {
        let exact = self.files.iter().find_map(|(p, f)| {
            f.find_identity(vendor_id, product_code, Some(revision))
                .map(|d| (p.as_path(), d, true))
        });
        exact.or_else(|| {
            self.files
                .iter()
                .filter_map(|(p, f)| {
                    f.find_identity(vendor_id, product_code, None)
                        .map(|d| (p.as_path(), d, false))
                })
                .max_by_key(|(_, d, _)| d.revision)
        })
    }
}

/// Why a line cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum LineError {
    /// Slaves nothing matched.
    #[error("no device for {}", .0.join("; "))]
    Unmatched(Vec<String>),
    /// A matched device cannot be twinned.
    #[error("slave {position} ({name}): {source}")]
    Twin {
        /// Line position (0-based).
        position: usize,
        /// ENI name.
        name: String,
        /// Why.
        source: Box<TwinError>,
    },
}

/// A built line: the slaves in order and where each came from.
pub struct BuiltLine {
    /// The software slaves, first to last.
    pub slaves: Vec<Box<dyn LineSlave>>,
    /// Where each came from (for the report).
    pub placed: Vec<Placed>,
}

impl core::fmt::Debug for BuiltLine {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("BuiltLine")
            .field("placed", &self.placed)
            .finish_non_exhaustive()
    }
}

/// Where one slave of the line came from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Source {
    /// A built-in device of the catalog (its key).
    BuiltIn(String),
    /// A device of an ESI file; `exact` false when the revision differs.
    Esi {
        /// The file.
        path: PathBuf,
        /// Type name.
        type_name: String,
        /// Revision the twin has.
        revision: u32,
        /// The ENI's revision was found.
        exact: bool,
    },
}

/// One slave of a built line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Placed {
    /// The ENI slave.
    pub eni: EniSlave,
    /// What runs it.
    pub source: Source,
}

impl Placed {
    /// One line of the report `pam-slave --eni` prints.
    pub fn report(&self) -> String {
        let what = match &self.source {
            Source::BuiltIn(key) => format!("built-in device '{key}'"),
            Source::Esi {
                path,
                type_name,
                revision,
                exact,
            } => format!(
                "{type_name} rev {revision:#010x} from {}{}",
                path.display(),
                if *exact {
                    ""
                } else {
                    " (the ENI's revision is not in the file: highest revision taken)"
                }
            ),
        };
        format!(
            "{:#06x} {:<28} vendor {:#010x} product {:#010x} rev {:#010x}{}: {what}",
            self.eni.phys_addr,
            self.eni.name,
            self.eni.vendor_id,
            self.eni.product_code,
            self.eni.revision,
            self.eni
                .alias
                .map_or(String::new(), |a| format!(" alias {a}")),
        )
    }
}

/// The module idents the ENI configures for a modular slave: what its
/// CoE init commands write into 0xF030 (the configured module ident list
/// TwinCAT downloads), sub 0 giving the count; `None` when it writes none.
/// A twin of the slave detects exactly these modules, as the real line
/// would hold them.
pub fn configured_modules(s: &EniSlave) -> Option<Vec<u32>> {
    let mut idents: Vec<(u8, u32)> = Vec::new();
    let mut count = None;
    for c in s.coe_init.iter().filter(|c| c.index == 0xF030) {
        let word = |k: usize| {
            c.data
                .get(4 * k..4 * k + 4)
                .and_then(|b| b.try_into().ok())
                .map(u32::from_le_bytes)
        };
        if c.complete_access {
            // Sub 0 (one byte, padded to two), then the idents.
            let n = c.data.first().copied().unwrap_or(0);
            count = Some(n);
            let body = c.data.get(2..).unwrap_or(&[]);
            for k in 0..usize::from(n) {
                if let Some(v) = body.get(4 * k..4 * k + 4).and_then(|b| b.try_into().ok()) {
                    idents.push((
                        u8::try_from(k + 1).unwrap_or(u8::MAX),
                        u32::from_le_bytes(v),
                    ));
                }
            }
        } else if c.sub == 0 {
            count = c.data.first().copied();
        } else if let Some(v) = word(0) {
            idents.retain(|(s, _)| *s != c.sub);
            idents.push((c.sub, v));
        }
    }
    let n = count?;
    idents.sort_by_key(|(s, _)| *s);
    Some(
        idents
            .into_iter()
            .filter(|(s, _)| *s >= 1 && *s <= n)
            .map(|(_, v)| v)
            .collect(),
    )
}

/// A built-in device for an ENI slave, if the caller has one: its key and
/// a slave in its power-on state.
pub type BuiltIn<'a> = &'a dyn Fn(&EniSlave) -> Option<(String, Box<dyn LineSlave>)>;

/// The slaves of `eni` in line order, from `builtin` or `lib`; their input
/// rules are `rules`.
pub fn build(
    eni: &[EniSlave],
    lib: &EsiLibrary,
    builtin: BuiltIn<'_>,
    rules: &InputRules,
) -> Result<BuiltLine, LineError> {
    let mut slaves = Vec::new();
    let mut placed = Vec::new();
    let mut unmatched = Vec::new();
    for (position, s) in eni.iter().enumerate() {
        if let Some((key, mut slave)) = builtin(s) {
            if let Some(a) = s.alias {
                slave.esc_mut().program_sii_alias(a);
                slave.esc_mut().power_on();
            }
            slaves.push(slave);
            placed.push(Placed {
                eni: s.clone(),
                source: Source::BuiltIn(key),
            });
            continue;
        }
        match lib.find(s.vendor_id, s.product_code, s.revision) {
            Some((path, dev, exact)) => {
                let modules = configured_modules(s);
                let t = twin_with_modules(
                    dev,
                    s.alias,
                    rules.for_type(&dev.type_name),
                    modules.as_deref(),
                )
                .map_err(|source| LineError::Twin {
                    position,
                    name: s.name.clone(),
                    source: Box::new(source),
                })?;
                slaves.push(t);
                placed.push(Placed {
                    eni: s.clone(),
                    source: Source::Esi {
                        path: path.to_path_buf(),
                        type_name: dev.type_name.clone(),
                        revision: dev.revision,
                        exact,
                    },
                });
            }
            None => unmatched.push(format!(
                "slave {position} '{}' ({}, vendor {:#x} product {:#010x} rev {:#010x})",
                s.name, s.at, s.vendor_id, s.product_code, s.revision
            )),
        }
    }
    if !unmatched.is_empty() {
        return Err(LineError::Unmatched(unmatched));
    }
    Ok(BuiltLine { slaves, placed })
}
