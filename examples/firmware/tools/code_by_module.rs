//! Where a Cortex-M firmware's code goes, by source module.
//!
//!     code_by_module [--lines | --functions] <linked-elf-with-debug-info> [top]
//!     code_by_module --diff <old-elf> <new-elf> [top]
//!
//! Reads the Thumb-2 disassembly (`$OBJDUMP`, default
//! `arm-none-eabi-objdump -d`) for the address and size of every
//! instruction, asks `$ADDR2LINE` (default `arm-none-eabi-addr2line -i`)
//! for the chain of inlined frames at each address, and counts each
//! instruction's bytes for the innermost frame in a source file of this
//! repository (`slave/`, `devices/`, `examples/`, `drivers/`,
//! `profiles/`): `core`'s `Option`, `Result` and slice code inlined into
//! the core counts for the module that uses it. Code with no frame of
//! ours (compiler builtins such as memcpy, `core` functions kept out of
//! line) counts for the innermost file named.
//!
//! With `--lines`, counts by source line (`file:line`) instead of file:
//! where in a module the bytes are (a line inlined at several call sites
//! counts once with all their bytes). With `--functions`, by the
//! innermost function of ours (`addr2line -f -C`): the bytes a function
//! brings wherever LTO inlined it, which `nm` cannot say (a function
//! inlined into `fw_poll` has no symbol of its own).
//!
//! With `--diff`, what a change did: both builds counted by function,
//! and the `top` largest differences (new minus old) either way, so a size
//! step shows where its bytes went or came from.
//!
//! Prints the `top` (default 40) files by bytes, then the totals of the
//! areas the footprint table of docs/book/src/performance.md uses. LTO
//! inlines nearly everything into `fw_poll`, so symbol sizes (`nm`) say
//! little; this does. The figures are of the debug-info build, whose code
//! may differ from the release build's by a few bytes.
//!
//! Only `std`: built by scripts/footprint.sh with `rustc -O`.

use std::collections::BTreeMap;
use std::io::Write;
use std::process::{Command, Stdio, exit};

/// Path prefixes of this repository's crates, after the checkout's root.
const OURS: [&str; 5] = ["slave/", "devices/", "examples/", "drivers/", "profiles/"];

/// The areas of the footprint table: (label, path prefixes).
const AREAS: [(&str, &[&str]); 12] = [
    (
        "device API (device/: poll, AL transitions, mailbox, SDO adapter)",
        &["slave/src/device/"],
    ),
    (
        "firmware update (FoE, .efw check, A/B store, boot state)",
        &[
            "slave/src/firmware/",
            "slave/src/foe.rs",
            "slave/src/wire/foe.rs",
        ],
    ),
    (
        "object dictionary and parameters (od/, params)",
        &["slave/src/od/", "slave/src/params.rs"],
    ),
    ("SDO Information", &["slave/src/coe/sdo_info.rs"]),
    ("CoE: SDO, emergencies", &["slave/src/coe/"]),
    ("wire formats (wire/)", &["slave/src/wire/"]),
    ("PDO engine (pdo.rs)", &["slave/src/pdo.rs"]),
    (
        "AL state machine, mailbox, texts, rest of the core",
        &["slave/"],
    ),
    (
        "the device's application and board",
        &["devices/", "examples/io8/", "profiles/"],
    ),
    (
        "the firmware example's glue and board stores",
        &["examples/firmware/"],
    ),
    ("the PDI trait and SPI drivers (drivers/)", &["drivers/"]),
    (
        "core, compiler builtins, the C library and other crates",
        &[""],
    ),
];

fn tool(var: &str, default: &str) -> String {
    std::env::var(var).unwrap_or_else(|_| default.to_string())
}

/// The path of `file` from the checkout's root for our crates (the part
/// from the first of [`OURS`] on), else from `library/` or the crate's
/// registry directory on.
fn short(file: &str) -> Option<String> {
    for p in OURS {
        if let Some(i) = file.find(&format!("/{p}")) {
            return Some(file[i + 1..].to_string());
        }
    }
    None
}

/// A demangled name without generic arguments (`a::B<T>::f` →
/// `a::B::f`), so the instances of one function count together; a trait
/// method keeps its `<Type as Trait>` head, shortened the same way.
fn short_name(name: &str) -> String {
    if let Some(rest) = name.strip_prefix('<') {
        // The head's closing '>' at depth 0.
        let mut depth = 0usize;
        for (i, c) in rest.char_indices() {
            match c {
                '<' => depth += 1,
                '>' if depth == 0 => {
                    let (head, tail) = rest.split_at(i);
                    return format!("<{}>{}", short_name(head), short_name(&tail[1..]));
                }
                '>' => depth -= 1,
                _ => {}
            }
        }
    }
    let mut out = String::new();
    let mut depth = 0usize;
    for (i, c) in name.char_indices() {
        match c {
            // `m::<impl m::Type>::f`: the impl block, named as such.
            '<' if depth == 0 && name[i + 1..].starts_with("impl ") => {
                out.push_str("<impl>");
                depth += 1;
            }
            '<' => depth += 1,
            '>' => depth = depth.saturating_sub(1),
            _ if depth == 0 => out.push(c),
            _ => {}
        }
    }
    out
}

fn other(file: &str) -> String {
    for key in ["/library/", "/compiler-builtins/", "/registry/src/"] {
        if let Some(i) = file.find(key) {
            let rest = &file[i + key.len()..];
            // registry paths: index.crates.io-xxxx/crate-1.2.3/src/...
            let rest = if key == "/registry/src/" {
                rest.split_once('/').map_or(rest, |(_, r)| r)
            } else {
                rest
            };
            return format!("{}{}", key.trim_start_matches('/'), rest);
        }
    }
    file.to_string()
}

/// Bytes of code of one ELF: the total, by file (or file:line), and with
/// `functions` by function.
struct Measured {
    total: u64,
    by_file: BTreeMap<String, u64>,
    by_func: BTreeMap<String, u64>,
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let diff = args.first().is_some_and(|a| a == "--diff");
    let lines = args.first().is_some_and(|a| a == "--lines");
    let functions = args.first().is_some_and(|a| a == "--functions");
    if lines || functions || diff {
        args.remove(0);
    }
    if diff {
        let (Some(old), Some(new)) = (args.first(), args.get(1)) else {
            eprintln!("usage: code_by_module --diff <old-elf> <new-elf> [top]");
            exit(2);
        };
        let top: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(40);
        print_diff(&measure(old, false, true), &measure(new, false, true), top);
        return;
    }
    let Some(elf) = args.first() else {
        eprintln!(
            "usage: code_by_module [--lines | --functions] <linked-elf-with-debug-info> [top]\n       code_by_module --diff <old-elf> <new-elf> [top]"
        );
        exit(2);
    };
    let top: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(40);
    let Measured {
        total,
        by_file,
        by_func,
    } = measure(elf, lines, functions);

    if functions {
        let mut fs: Vec<(&String, &u64)> = by_func.iter().collect();
        fs.sort_by(|a, b| b.1.cmp(a.1).then(a.0.cmp(b.0)));
        println!("    {total} bytes of code; by the innermost function of this repository:");
        for (f, n) in fs.iter().take(top) {
            println!("    {n:7} {f}");
        }
        if fs.len() > top {
            let rest: u64 = fs.iter().skip(top).map(|(_, n)| **n).sum();
            println!("    {rest:7} ({} more functions)", fs.len() - top);
        }
        return;
    }

    let unit = if lines { "line" } else { "file" };
    println!("    {total} bytes of code; by the innermost source {unit} of this repository:");
    let mut files: Vec<(&String, &u64)> = by_file.iter().collect();
    files.sort_by(|a, b| b.1.cmp(a.1).then(a.0.cmp(b.0)));
    for (f, n) in files.iter().take(top) {
        println!("    {n:7} {f}");
    }
    if files.len() > top {
        let rest: u64 = files.iter().skip(top).map(|(_, n)| **n).sum();
        println!("    {rest:7} ({} more {unit}s)", files.len() - top);
    }
    println!("    by area:");
    let mut areas = [0u64; AREAS.len()];
    for (f, n) in &by_file {
        let k = AREAS
            .iter()
            .position(|(_, ps)| ps.iter().any(|p| f.starts_with(p)))
            .unwrap_or(AREAS.len() - 1);
        areas[k] += n;
    }
    for ((label, _), n) in AREAS.iter().zip(areas) {
        println!("    {n:7} {label}");
    }
}

/// What a change did to the code, function by function: the `top`
/// largest differences (new minus old) either way, then the total.
fn print_diff(old: &Measured, new: &Measured, top: usize) {
    let keys: std::collections::BTreeSet<&String> =
        old.by_func.keys().chain(new.by_func.keys()).collect();
    let mut d: Vec<(i64, &String)> = keys
        .into_iter()
        .map(|k| {
            let n = |m: &Measured| m.by_func.get(k).copied().unwrap_or(0) as i64;
            (n(new) - n(old), k)
        })
        .filter(|(d, _)| *d != 0)
        .collect();
    d.sort_by(|a, b| b.0.abs().cmp(&a.0.abs()).then(a.1.cmp(b.1)));
    println!(
        "    {} -> {} bytes of code ({:+}); the largest changes by the innermost function of this repository:",
        old.total,
        new.total,
        new.total as i64 - old.total as i64
    );
    for (n, f) in d.iter().take(top) {
        println!("    {n:+7} {f}");
    }
    if d.len() > top {
        let rest: i64 = d.iter().skip(top).map(|(n, _)| n).sum();
        println!("    {rest:+7} ({} more functions)", d.len() - top);
    }
}

/// Runs objdump and addr2line on `elf` and counts each instruction's bytes
/// for the innermost frame of ours (see the module docs).
fn measure(elf: &str, lines: bool, functions: bool) -> Measured {
    let objdump = tool("OBJDUMP", "arm-none-eabi-objdump");
    let out = Command::new(&objdump)
        .args(["-d", "--no-show-raw-insn", "-j", ".text", elf])
        .output()
        .unwrap_or_else(|e| {
            eprintln!("code_by_module: running {objdump}: {e}");
            exit(1)
        });
    if !out.status.success() {
        eprintln!("code_by_module: {objdump} failed on {elf}");
        exit(1);
    }
    let mut addrs: Vec<u64> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| {
            let (a, rest) = l.trim_start().split_once(':')?;
            // Instruction lines: "  8000:\tpush ..."; labels end in ">:".
            (l.starts_with(' ') && rest.starts_with('\t'))
                .then(|| u64::from_str_radix(a, 16).ok())
                .flatten()
        })
        .collect();
    addrs.sort_unstable();
    addrs.dedup();
    if addrs.is_empty() {
        eprintln!("code_by_module: no instructions in {elf}");
        exit(1);
    }

    let addr2line = tool("ADDR2LINE", "arm-none-eabi-addr2line");
    let mut a2l_args = vec!["-e", elf, "-i", "-a"];
    if functions {
        a2l_args.extend(["-f", "-C"]);
    }
    let mut child = Command::new(&addr2line)
        .args(&a2l_args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| {
            eprintln!("code_by_module: running {addr2line}: {e}");
            exit(1)
        });
    let input: String = addrs.iter().map(|a| format!("{a:#x}\n")).collect();
    let mut stdin = child.stdin.take().expect("piped stdin");
    let writer = std::thread::spawn(move || stdin.write_all(input.as_bytes()));
    let out = child.wait_with_output().unwrap_or_else(|e| {
        eprintln!("code_by_module: {addr2line}: {e}");
        exit(1)
    });
    if writer.join().map_or(true, |r| r.is_err()) || !out.status.success() {
        eprintln!("code_by_module: {addr2line} failed on {elf}");
        exit(1);
    }

    // Frames per address, innermost first (addr2line -i's order): the
    // file (or file:line), and with --functions the function's name.
    let mut frames: BTreeMap<u64, Vec<String>> = BTreeMap::new();
    let mut names: BTreeMap<u64, Vec<String>> = BTreeMap::new();
    let mut cur = None;
    // With -f each frame is two lines: the function, then its location.
    let mut name: Option<String> = None;
    for line in String::from_utf8_lossy(&out.stdout).lines() {
        if let Some(hex) = line.strip_prefix("0x") {
            cur = u64::from_str_radix(hex, 16).ok();
            name = None;
        } else if let Some(a) = cur {
            if functions && name.is_none() {
                name = Some(line.to_string());
                continue;
            }
            // "file:line (discriminator n)": the file, or file and line.
            let at = line.split(" (discriminator").next().unwrap_or(line);
            let file = if lines {
                at
            } else {
                at.rsplit_once(':').map_or(at, |(f, _)| f)
            };
            frames.entry(a).or_default().push(file.to_string());
            if let Some(n) = name.take() {
                names.entry(a).or_default().push(n);
            }
        }
    }

    let mut by_file: BTreeMap<String, u64> = BTreeMap::new();
    let mut by_func: BTreeMap<String, u64> = BTreeMap::new();
    let mut total = 0;
    for (i, &a) in addrs.iter().enumerate() {
        // Thumb-2 instructions are 2 or 4 bytes; the last one, or one
        // before padding, is counted as 2.
        let size = addrs.get(i + 1).map_or(2, |n| (n - a).min(4));
        total += size;
        let fr = frames.get(&a);
        let ours = fr.and_then(|f| f.iter().position(|f| short(f).is_some()));
        let file = fr
            .and_then(|f| f.iter().find_map(|f| short(f)))
            .or_else(|| fr.and_then(|f| f.first()).map(|f| other(f)))
            .unwrap_or_else(|| "??".to_string());
        if functions {
            // The function whose body holds the innermost frame of ours
            // (the frame's location is inside that function).
            let f = names.get(&a);
            let func = ours
                .and_then(|i| f.and_then(|f| f.get(i)))
                .or_else(|| f.and_then(|f| f.first()))
                .map_or_else(|| "??".to_string(), |n| short_name(n));
            *by_func.entry(func).or_default() += size;
        }
        *by_file.entry(file).or_default() += size;
    }
    Measured {
        total,
        by_file,
        by_func,
    }
}
