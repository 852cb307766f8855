//! Static worst-case stack estimate from an x86-64 or Thumb-2 disassembly.
//!
//!     stack_estimate <linked-binary> <root-function>...
//!     stack_estimate --thumb <linked-binary> <root-function>...
//!
//! `--thumb` reads a Cortex-M (Thumb-2) binary with `$OBJDUMP` (default
//! `arm-none-eabi-objdump`): a frame is every `push`/`stmdb sp!` (4 bytes
//! per register), `vpush` (4 per s-, 8 per d-register) and `sub sp` by an
//! immediate; `bl` is a call, `b`/`b.w` into another function a tail
//! call, `blx`/`bx` through a register other than `lr` an indirect call;
//! function addresses in data and literal pools (Thumb bit set) are the
//! address-taken ones. The return address is in `lr` and counted by the
//! `push` that saves it. The x86-64 mode:
//!
//! Reads `objdump -d -C -w` of the binary (binutils) and, per function,
//! its frame: the return address (8), every `push` (8 each) and every
//! `sub $N,%rsp` / `add $-N,%rsp` (stack probes of big frames included;
//! pushes and subs on any path are summed, so a frame is never
//! under-counted). Edges of the call graph:
//!
//! * direct calls and jumps into another function (tail calls);
//! * calls through a GOT slot (`call *N(%rip)`, how PIC Rust code calls C
//!   functions): the slot's content is read from the binary;
//! * indirect calls through a register or memory (`dyn Trait` vtables,
//!   function pointers) cannot be resolved: they are reported, and a
//!   second, conservative figure lets each reach any address-taken Rust
//!   function (any function whose address appears in data or is loaded by
//!   `lea` in code).
//!
//! Jump tables (`movslq (table,idx,4)` + `add` + `jmp *%reg`) stay inside
//! their function. Calls into shared libraries (libc `memcpy`, `memset`)
//! are listed and not included. Recursion is reported; a cycle is counted
//! once.
//!
//! Only `std`: built by scripts/footprint.sh with `rustc -O`.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::process::{Command, exit};

#[derive(Debug, Default)]
struct Func {
    name: String,
    start: u64,
    frame: u64,
    /// Direct callees (function start addresses).
    calls: BTreeSet<u64>,
    /// Tail-jump targets (function start addresses).
    tails: BTreeSet<u64>,
    /// Calls into shared libraries / unresolved symbols, by name.
    external: BTreeSet<String>,
    /// Indirect call sites (register or memory operand).
    indirect: usize,
    /// Stack pointer moved by a register amount (alloca-like).
    dynamic: bool,
}

/// The objdump of the binary's architecture (set by `--thumb`).
static DEFAULT_OBJDUMP: std::sync::OnceLock<&str> = std::sync::OnceLock::new();

fn objdump(args: &[&str]) -> String {
    let tool = std::env::var("OBJDUMP")
        .unwrap_or_else(|_| DEFAULT_OBJDUMP.get().copied().unwrap_or("objdump").into());
    let out = Command::new(tool)
        .args(args)
        .output()
        .unwrap_or_else(|e| {
            eprintln!("stack_estimate: cannot run objdump: {e}");
            exit(2)
        });
    if !out.status.success() {
        eprintln!("stack_estimate: objdump {:?} failed", args);
        exit(2);
    }
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn hex(s: &str) -> Option<u64> {
    u64::from_str_radix(s.trim().trim_start_matches("0x"), 16).ok()
}

/// Immediate of an operand like `$0x1a8` or `$-0x80`.
fn imm(op: &str) -> Option<i64> {
    let v = op.strip_prefix('$')?;
    let (neg, v) = match v.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, v),
    };
    let n = i64::from_str_radix(v.strip_prefix("0x")?, 16).ok()?;
    Some(if neg { -n } else { n })
}

/// Bytes of the allocated sections holding data, by address.
fn data_bytes(bin: &str) -> BTreeMap<u64, Vec<u8>> {
    let text = objdump(&[
        "-s",
        "-j",
        ".got",
        "-j",
        ".data.rel.ro",
        "-j",
        ".rodata",
        "-j",
        ".data",
        bin,
    ]);
    let mut chunks = BTreeMap::new();
    for line in text.lines() {
        let line = line.trim_start();
        let mut parts = line.split(' ');
        let Some(addr) = parts.next().and_then(hex) else {
            continue;
        };
        let mut bytes = Vec::new();
        for word in parts.take(4) {
            if word.is_empty() || word.len() % 2 != 0 || hex(word).is_none() {
                break;
            }
            for i in (0..word.len()).step_by(2) {
                bytes.push(u8::from_str_radix(&word[i..i + 2], 16).unwrap_or(0));
            }
        }
        if !bytes.is_empty() {
            chunks.insert(addr, bytes);
        }
    }
    chunks
}

fn read_u64(data: &BTreeMap<u64, Vec<u8>>, addr: u64) -> Option<u64> {
    let mut out = [0u8; 8];
    for (i, b) in out.iter_mut().enumerate() {
        let a = addr + i as u64;
        let (base, chunk) = data.range(..=a).next_back()?;
        *b = *chunk.get((a - base) as usize)?;
    }
    Some(u64::from_le_bytes(out))
}

/// The name between the first `<` and the last `>` of `s`.
fn sym(s: &str) -> Option<&str> {
    let a = s.find('<')?;
    let b = s.rfind('>')?;
    (b > a).then(|| &s[a + 1..b])
}

fn parse(bin: &str) -> (BTreeMap<u64, Func>, BTreeSet<u64>) {
    let text = objdump(&["-d", "-C", "-w", "--no-show-raw-insn", bin]);
    let data = data_bytes(bin);
    // First pass: function starts.
    let mut starts: BTreeMap<u64, String> = BTreeMap::new();
    for line in text.lines() {
        if let (Some(sp), true) = (line.find(" <"), line.ends_with(">:")) {
            if let Some(a) = hex(&line[..sp]) {
                starts.insert(a, line[sp + 2..line.len() - 2].to_string());
            }
        }
    }
    let owner = |a: u64| starts.range(..=a).next_back().map(|(s, _)| *s);
    let mut funcs: BTreeMap<u64, Func> = BTreeMap::new();
    let mut taken: BTreeSet<u64> = BTreeSet::new();
    // Function addresses stored in data (vtables, function pointer tables).
    for (base, chunk) in &data {
        for off in (0..chunk.len()).step_by(8) {
            if let Some(v) = read_u64(&data, base + off as u64) {
                if starts.contains_key(&v) {
                    taken.insert(v);
                }
            }
        }
    }
    let mut cur: Option<u64> = None;
    let mut recent: Vec<String> = Vec::new();
    let mut r11_probe = false;
    let mut probe_subs: u64 = 0;
    let finish = |f: &mut Func, r11: bool, probe: u64| {
        if r11 {
            // Probe loop: `sub $0x1000,%rsp` repeats until %r11; the total
            // came from `sub $N,%r11`, the loop's own sub is not extra.
            f.frame = f.frame.saturating_sub(probe);
        }
    };
    for line in text.lines() {
        if let (Some(sp), true) = (line.find(" <"), line.ends_with(">:")) {
            if let Some(c) = cur {
                if let Some(f) = funcs.get_mut(&c) {
                    finish(f, r11_probe, probe_subs);
                }
            }
            let Some(a) = hex(&line[..sp]) else { continue };
            funcs.insert(
                a,
                Func {
                    name: line[sp + 2..line.len() - 2].to_string(),
                    start: a,
                    frame: 8,
                    ..Func::default()
                },
            );
            cur = Some(a);
            recent.clear();
            r11_probe = false;
            probe_subs = 0;
            continue;
        }
        let Some(c) = cur else { continue };
        let Some(colon) = line.find(':') else {
            continue;
        };
        if hex(&line[..colon]).is_none() {
            continue;
        }
        let mut ins = line[colon + 1..].trim();
        for p in [
            "notrack ", "bnd ", "lock ", "rep ", "repz ", "repnz ", "data16 ", "cs ",
        ] {
            if let Some(rest) = ins.strip_prefix(p) {
                ins = rest.trim_start();
            }
        }
        let (body, comment) = match ins.find('#') {
            Some(h) => (ins[..h].trim(), Some(ins[h + 1..].trim())),
            None => (ins, None),
        };
        let mut it = body.splitn(2, char::is_whitespace);
        let mn = it.next().unwrap_or("");
        let ops = it.next().unwrap_or("").trim();
        let f = funcs.get_mut(&c).expect("current function");
        let mn_base = mn.trim_end_matches('q');
        if mn.starts_with("push") {
            f.frame += 8;
        } else if mn_base == "sub" || mn_base == "add" {
            if let Some((src, dst)) = ops.split_once(',') {
                let v = imm(src);
                match (dst, v) {
                    ("%rsp", Some(n)) => {
                        let n = if mn_base == "sub" { n } else { -n };
                        if n > 0 {
                            f.frame += n as u64;
                            if n == 0x1000 {
                                probe_subs += 0x1000;
                            }
                        }
                    }
                    ("%r11", Some(n)) if mn_base == "sub" && n > 0 => {
                        if recent.iter().any(|r| r.contains("%rsp,%r11")) {
                            r11_probe = true;
                            f.frame += n as u64;
                        }
                    }
                    ("%rsp", None) if mn_base == "sub" => f.dynamic = true,
                    _ => {}
                }
            }
        } else if mn == "call" || mn == "callq" || mn.starts_with('j') {
            let is_call = mn.starts_with("call");
            if let Some(target) = ops.strip_prefix('*') {
                if target.contains("(%rip)") {
                    // Through a GOT slot: read its content.
                    let slot = comment
                        .and_then(|c| c.split_whitespace().next())
                        .and_then(hex);
                    let dest = slot
                        .and_then(|s| read_u64(&data, s))
                        .filter(|d| starts.contains_key(d));
                    match dest {
                        Some(d) if is_call => {
                            f.calls.insert(d);
                        }
                        Some(d) => {
                            f.tails.insert(d);
                        }
                        None => {
                            let name = comment.and_then(sym).unwrap_or("?").to_string();
                            f.external.insert(name);
                        }
                    }
                } else if is_call {
                    f.indirect += 1;
                } else {
                    let table = recent.iter().rev().take(4).any(|r| r.contains("movslq ("));
                    if !table {
                        f.indirect += 1;
                    }
                }
            } else if let Some(t) = ops.split_whitespace().next().and_then(hex) {
                let name = sym(ops).unwrap_or("");
                if name.ends_with("@plt") {
                    f.external.insert(name.trim_end_matches("@plt").to_string());
                } else if let Some(o) = owner(t) {
                    if o != c || (is_call && t == c) {
                        if is_call {
                            f.calls.insert(o);
                        } else {
                            f.tails.insert(o);
                        }
                    }
                }
            }
        } else if mn == "lea" {
            // A function address taken in code (function pointers).
            if let Some(a) = comment
                .and_then(|c| c.split_whitespace().next())
                .and_then(hex)
            {
                if starts.contains_key(&a) {
                    taken.insert(a);
                }
            }
        }
        recent.push(body.to_string());
        if recent.len() > 6 {
            recent.remove(0);
        }
    }
    if let Some(c) = cur {
        if let Some(f) = funcs.get_mut(&c) {
            finish(f, r11_probe, probe_subs);
        }
    }
    // Indirect calls come from Rust code: only Rust functions are targets.
    let rust: BTreeSet<u64> = taken
        .into_iter()
        .filter(|a| {
            funcs.get(a).is_some_and(|f| {
                f.name.contains("::") || f.name.starts_with("_ZN") || f.name.starts_with("_R")
            })
        })
        .collect();
    (funcs, rust)
}

/// Registers in an ARM register list `{r4, r5, lr}` / `{d8-d10}`, and
/// the bytes they take on the stack.
fn reg_list_bytes(ops: &str) -> u64 {
    let Some(a) = ops.find('{') else { return 0 };
    let Some(b) = ops[a..].find('}') else { return 0 };
    let mut bytes = 0;
    for item in ops[a + 1..a + b].split(',') {
        let item = item.trim();
        let width = if item.starts_with('d') { 8 } else { 4 };
        let count = match item.split_once('-') {
            Some((x, y)) => {
                let n = |r: &str| r.trim_start_matches(|c: char| c.is_alphabetic()).parse::<u64>().ok();
                match (n(x), n(y)) {
                    (Some(x), Some(y)) if y >= x => y - x + 1,
                    _ => 1,
                }
            }
            None => 1,
        };
        bytes += width * count;
    }
    bytes
}

/// The Thumb-2 (Cortex-M) parse: see the module docs.
fn parse_thumb(bin: &str) -> (BTreeMap<u64, Func>, BTreeSet<u64>) {
    let text = objdump(&["-d", "-C", "-w", "--no-show-raw-insn", bin]);
    let data = data_bytes(bin);
    let mut starts: BTreeMap<u64, String> = BTreeMap::new();
    for line in text.lines() {
        if let (Some(sp), true) = (line.find(" <"), line.ends_with(">:")) {
            if let Some(a) = hex(&line[..sp]) {
                starts.insert(a, line[sp + 2..line.len() - 2].to_string());
            }
        }
    }
    let owner = |a: u64| starts.range(..=a).next_back().map(|(s, _)| *s);
    let mut taken: BTreeSet<u64> = BTreeSet::new();
    let note = |v: u64, taken: &mut BTreeSet<u64>| {
        if v & 1 == 1 && starts.contains_key(&(v & !1)) {
            taken.insert(v & !1);
        }
    };
    for (base, chunk) in &data {
        for off in (0..chunk.len().saturating_sub(3)).step_by(4) {
            let w = u32::from_le_bytes([chunk[off], chunk[off + 1], chunk[off + 2], chunk[off + 3]]);
            let _ = base;
            note(u64::from(w), &mut taken);
        }
    }
    let mut funcs: BTreeMap<u64, Func> = BTreeMap::new();
    let mut cur: Option<u64> = None;
    for line in text.lines() {
        if let (Some(sp), true) = (line.find(" <"), line.ends_with(">:")) {
            let Some(a) = hex(&line[..sp]) else { continue };
            funcs.insert(
                a,
                Func {
                    name: line[sp + 2..line.len() - 2].to_string(),
                    start: a,
                    frame: 0,
                    ..Func::default()
                },
            );
            cur = Some(a);
            continue;
        }
        let Some(c) = cur else { continue };
        let Some(colon) = line.find(':') else { continue };
        if hex(&line[..colon]).is_none() {
            continue;
        }
        let ins = line[colon + 1..].trim();
        let body = ins.split(';').next().unwrap_or("").split('@').next().unwrap_or("").trim();
        let mut it = body.splitn(2, char::is_whitespace);
        let mn = it.next().unwrap_or("");
        let ops = it.next().unwrap_or("").trim();
        let Some(f) = funcs.get_mut(&c) else { continue };
        let mn_base = mn.split('.').next().unwrap_or(mn);
        match mn_base {
            ".word" => {
                if let Some(v) = hex(ops) {
                    note(v, &mut taken);
                }
            }
            "push" | "vpush" => f.frame += reg_list_bytes(ops),
            "stmdb" | "stmfd" if ops.starts_with("sp!") => f.frame += reg_list_bytes(ops),
            "sub" | "subw" => {
                let parts: Vec<&str> = ops.split(',').map(str::trim).collect();
                if parts.first() == Some(&"sp") {
                    match parts.last().and_then(|v| v.strip_prefix('#')) {
                        Some(v) => {
                            let n = v
                                .strip_prefix("0x")
                                .map_or_else(|| v.parse::<u64>().ok(), |h| u64::from_str_radix(h, 16).ok());
                            f.frame += n.unwrap_or(0);
                        }
                        None => f.dynamic = true,
                    }
                }
            }
            "str" if ops.contains("[sp, #-") && ops.ends_with("]!") => f.frame += 4,
            "bl" | "b" | "blx" | "bx" | "cbz" | "cbnz" | "beq" | "bne" | "bcs" | "bcc" | "bhi"
            | "bls" | "bge" | "blt" | "bgt" | "ble" | "bmi" | "bpl" | "bhs" | "blo" => {
                let is_call = mn_base == "bl" || mn_base == "blx";
                let target = ops.split(',').next_back().unwrap_or("").trim();
                match target.split_whitespace().next().and_then(hex) {
                    Some(t) if target.contains('<') => {
                        if let Some(o) = owner(t) {
                            if o != c || (is_call && t == c) {
                                if is_call {
                                    f.calls.insert(o);
                                } else {
                                    f.tails.insert(o);
                                }
                            }
                        }
                    }
                    _ if (mn_base == "blx" || mn_base == "bx") && target != "lr" => f.indirect += 1,
                    _ => {}
                }
            }
            _ => {}
        }
    }
    let rust: BTreeSet<u64> = taken
        .into_iter()
        .filter(|a| {
            funcs.get(a).is_some_and(|f| {
                f.name.contains("::") || f.name.starts_with("_ZN") || f.name.starts_with("_R")
            })
        })
        .collect();
    (funcs, rust)
}

struct Walk<'a> {
    funcs: &'a BTreeMap<u64, Func>,
    /// Added at each function with indirect call sites (0: not followed).
    indirect_cost: u64,
    memo: HashMap<u64, (u64, Vec<u64>)>,
    on_stack: Vec<u64>,
    cycles: BTreeSet<String>,
}

impl<'a> Walk<'a> {
    fn new(funcs: &'a BTreeMap<u64, Func>, indirect_cost: u64) -> Self {
        Walk {
            funcs,
            indirect_cost,
            memo: HashMap::new(),
            on_stack: Vec::new(),
            cycles: BTreeSet::new(),
        }
    }

    /// Worst stack of `f` (its return address included) and the path.
    fn total(&mut self, f: u64) -> (u64, Vec<u64>) {
        if let Some(r) = self.memo.get(&f) {
            return r.clone();
        }
        if let Some(pos) = self.on_stack.iter().position(|x| *x == f) {
            let names: Vec<&str> = self.on_stack[pos..]
                .iter()
                .chain(std::iter::once(&f))
                .map(|a| self.funcs.get(a).map_or("?", |x| x.name.as_str()))
                .collect();
            self.cycles.insert(names.join(" -> "));
            return (0, Vec::new());
        }
        let Some(func) = self.funcs.get(&f) else {
            return (0, Vec::new());
        };
        self.on_stack.push(f);
        let mut best_call = (0u64, Vec::new());
        if func.indirect > 0 {
            best_call.0 = self.indirect_cost;
        }
        for g in func.calls.iter().copied() {
            let r = self.total(g);
            if r.0 > best_call.0 {
                best_call = r;
            }
        }
        let mut path = vec![f];
        path.extend(best_call.1);
        let mut best = (func.frame + best_call.0, path);
        for g in func.tails.iter().copied() {
            let r = self.total(g);
            if r.0 > best.0 {
                let mut p = vec![f];
                p.extend(r.1);
                best = (r.0, p);
            }
        }
        self.on_stack.pop();
        self.memo.insert(f, best.clone());
        best
    }
}

fn reachable(funcs: &BTreeMap<u64, Func>, root: u64) -> BTreeSet<u64> {
    let mut seen = BTreeSet::new();
    let mut todo = vec![root];
    while let Some(f) = todo.pop() {
        if !seen.insert(f) {
            continue;
        }
        if let Some(func) = funcs.get(&f) {
            todo.extend(func.calls.iter().chain(func.tails.iter()));
        }
    }
    seen
}

fn short(name: &str, width: usize) -> String {
    if name.chars().count() <= width {
        return name.to_string();
    }
    let tail: String = name
        .chars()
        .rev()
        .take(width - 1)
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
        .collect();
    format!("…{tail}")
}

fn main() {
    let mut args: Vec<String> = std::env::args().collect();
    let thumb = args.get(1).is_some_and(|a| a == "--thumb");
    if thumb {
        args.remove(1);
        let _ = DEFAULT_OBJDUMP.set("arm-none-eabi-objdump");
    }
    if args.len() < 3 {
        eprintln!("usage: stack_estimate [--thumb] <binary> <root-function>...");
        exit(2);
    }
    let (funcs, taken) = if thumb { parse_thumb(&args[1]) } else { parse(&args[1]) };
    // The deepest address-taken Rust function (direct calls only): what one
    // unresolved indirect call can add at most, if it does not itself go
    // through another indirect call.
    let mut w = Walk::new(&funcs, 0);
    let (deepest_taken, deepest_name) = taken
        .iter()
        .map(|t| (w.total(*t).0, funcs[t].name.as_str()))
        .max()
        .unwrap_or((0, "-"));
    for root in &args[2..] {
        let Some(r) = funcs.values().find(|f| f.name == *root).map(|f| f.start) else {
            println!("  {root}: not found in the binary");
            continue;
        };
        let mut w = Walk::new(&funcs, 0);
        let (bytes, path) = w.total(r);
        let reach = reachable(&funcs, r);
        println!(
            "  {root}: {bytes} bytes on the worst path of direct calls ({} functions reachable):",
            reach.len()
        );
        let mut depth = 0;
        for a in &path {
            let f = &funcs[a];
            depth += f.frame;
            println!("      {:>6} {:>6}  {}", f.frame, depth, short(&f.name, 100));
        }
        println!("      (frame incl. return address, cumulative)");
        for c in &w.cycles {
            println!("      recursion (cycle counted once): {}", short(c, 200));
        }
        let ind: Vec<&Func> = reach
            .iter()
            .filter_map(|a| funcs.get(a))
            .filter(|f| f.indirect > 0)
            .collect();
        let sites: usize = ind.iter().map(|f| f.indirect).sum();
        if sites > 0 {
            let mut w1 = Walk::new(&funcs, deepest_taken);
            let (b1, _) = w1.total(r);
            println!(
                "  {root}: {b1} bytes if each of its {sites} indirect call sites (in {} functions: dyn ImageStore / NvStorage, core::fmt) reaches the deepest of the {} address-taken Rust functions ({deepest_taken} bytes, {}) through one level of indirection",
                ind.len(),
                taken.len(),
                short(deepest_name, 80)
            );
        }
        let ext: BTreeSet<&str> = reach
            .iter()
            .filter_map(|a| funcs.get(a))
            .flat_map(|f| f.external.iter().map(String::as_str))
            .collect();
        if !ext.is_empty() {
            println!(
                "      not included (shared library): {}",
                ext.into_iter()
                    .map(|e| e.split('@').next().unwrap_or(e))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        if reach
            .iter()
            .any(|a| funcs.get(a).is_some_and(|f| f.dynamic))
        {
            println!(
                "      WARNING: a reachable function moves the stack pointer by a register amount (alloca)"
            );
        }
    }
}
