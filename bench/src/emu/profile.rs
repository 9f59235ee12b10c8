//! Where the modeled cycles go: a per-block histogram (exception number × translated block,
//! with runs and cycles) kept while profiling is on, and the ELF's function symbols to name
//! the blocks. For the `sim` CLI (`--profile`), the sweep and anyone optimizing a handler.
//!
//! Blocks are unicorn's translated blocks; a block split by an exact event stop counts its
//! executed part. Exception entry and return are charged to pseudo-blocks so a handler's
//! total equals the step-ISR figures of the report.

use std::collections::HashMap;

use object::{Object, ObjectSymbol, SymbolKind};

/// Pseudo block address for the exception entry (stacking, vector fetch, tail-chain).
pub const ENTRY: u32 = 0xFFFF_FFF0;
/// Pseudo block address for the exception return (unstacking).
pub const RETURN: u32 = 0xFFFF_FFF4;

/// Runs and modeled cycles of one block in one exception context.
#[derive(Clone, Copy, Debug, Default)]
pub struct Count {
    pub runs: u64,
    pub cycles: u64,
    pub insns: u64,
}

/// The histogram: (exception number, block start) → count. Exception 0 is thread mode.
#[derive(Clone, Debug, Default)]
pub struct Histogram(pub HashMap<(u32, u32), Count>);

impl Histogram {
    // add one run of block `start` in exception `exc`
    pub fn add(&mut self, exc: u32, start: u32, cycles: u64, insns: u64) {
        let c = self.0.entry((exc, start)).or_default();
        c.runs += 1;
        c.cycles += cycles;
        c.insns += insns;
    }
}

/// Function symbols of the loaded ELF, sorted by address.
#[derive(Clone, Debug, Default)]
pub struct Symbols(Vec<(u32, u32, String)>);

impl Symbols {
    // text symbols of `elf` (names demangled)
    pub fn from_elf(elf: &[u8]) -> Self {
        let Ok(file) = object::File::parse(elf) else { return Self::default() };
        let mut v: Vec<(u32, u32, String)> = file
            .symbols()
            .filter(|s| s.kind() == SymbolKind::Text)
            .filter_map(|s| Some(((s.address() & !1) as u32, s.size() as u32, demangle(s.name().ok()?))))
            .collect();
        // sized symbols first at an address; an unsized one (hand-written assembly such as
        // compiler-builtins' `memcpy`) reaches to the next symbol
        v.sort_by(|a, b| a.0.cmp(&b.0).then(b.1.cmp(&a.1)).then(a.2.cmp(&b.2)));
        v.dedup_by_key(|s| s.0);
        for i in 0..v.len() {
            if v[i].1 == 0 {
                v[i].1 = v.get(i + 1).map_or(0, |n| n.0 - v[i].0);
            }
        }
        Self(v)
    }

    // start addresses of the functions whose demangled name (generics stripped, e.g.
    // `ddastep::grbl::controller::lines::<impl ddastep::grbl::controller::Controller<_>>::gcode`)
    // equals `name`
    pub fn addresses(&self, name: &str) -> Vec<u32> {
        self.0.iter().filter(|s| s.2 == name).map(|s| s.0).collect()
    }

    // start addresses of the functions whose demangled name ends with `suffix`
    pub fn addresses_ending(&self, suffix: &str) -> Vec<u32> {
        self.0.iter().filter(|s| s.2.ends_with(suffix)).map(|s| s.0).collect()
    }

    // the function containing `addr` and the offset into it
    pub fn lookup(&self, addr: u32) -> Option<(&str, u32)> {
        match addr {
            ENTRY => return Some(("(exception entry)", 0)),
            RETURN => return Some(("(exception return)", 0)),
            _ => {}
        }
        let i = self.0.partition_point(|s| s.0 <= addr).checked_sub(1)?;
        let (start, size, name) = &self.0[i];
        (addr < start + size.max(&1)).then_some((name.as_str(), addr - start))
    }
}

/// Cycles of one function within one exception context.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FnCost {
    pub function: String,
    pub cycles: u64,
    pub insns: u64,
    /// Block runs that started in this function.
    pub block_runs: u64,
    /// Share of the context's cycles.
    pub share: f64,
}

// per-function totals of exception `exc`, most expensive first
pub fn by_function(h: &Histogram, syms: &Symbols, exc: u32) -> Vec<FnCost> {
    let mut map: HashMap<String, (u64, u64, u64)> = HashMap::new();
    for (&(e, start), c) in &h.0 {
        if e != exc {
            continue;
        }
        let name = syms.lookup(start).map_or_else(|| format!("{start:#010x}"), |(n, _)| n.to_string());
        let t = map.entry(name).or_default();
        t.0 += c.cycles;
        t.1 += c.insns;
        t.2 += c.runs;
    }
    let total: u64 = map.values().map(|t| t.0).sum::<u64>().max(1);
    let mut v: Vec<FnCost> = map
        .into_iter()
        .map(|(function, (cycles, insns, block_runs))| FnCost { function, cycles, insns, block_runs, share: cycles as f64 / total as f64 })
        .collect();
    v.sort_by(|a, b| b.cycles.cmp(&a.cycles).then(a.function.cmp(&b.function)));
    v
}

// the blocks of exception `exc` by cycles, with symbol+offset names
pub fn by_block(h: &Histogram, syms: &Symbols, exc: u32) -> Vec<(String, Count)> {
    let mut v: Vec<(u32, Count)> = h.0.iter().filter(|((e, _), _)| *e == exc).map(|((_, a), c)| (*a, *c)).collect();
    v.sort_by(|a, b| b.1.cycles.cmp(&a.1.cycles).then(a.0.cmp(&b.0)));
    v.into_iter()
        .map(|(a, c)| {
            let name = match syms.lookup(a) {
                Some((n, 0)) => n.to_string(),
                Some((n, off)) => format!("{n}+{off:#x}"),
                None => format!("{a:#010x}"),
            };
            (format!("{a:#010x} {name}"), c)
        })
        .collect()
}

// legacy Rust symbol demangling (`_ZN...E`, hash dropped); a v0 name (`_R...`, e.g.
// compiler-builtins' soft float) as its crate and last identifier; other names pass through
pub fn demangle(sym: &str) -> String {
    if sym.starts_with("_R") {
        return demangle_v0_last(sym).unwrap_or_else(|| sym.to_string());
    }
    let Some(mut rest) = sym.strip_prefix("_ZN") else { return sym.to_string() };
    let mut parts = Vec::new();
    while let Some(len_end) = rest.find(|c: char| !c.is_ascii_digit()).filter(|&i| i > 0) {
        let Ok(len) = rest[..len_end].parse::<usize>() else { break };
        let Some(part) = rest.get(len_end..len_end + len) else { break };
        parts.push(part);
        rest = &rest[len_end + len..];
    }
    if parts.last().is_some_and(|p| p.len() == 17 && p.starts_with('h') && p[1..].chars().all(|c| c.is_ascii_hexdigit())) {
        parts.pop();
    }
    let parts: Vec<String> = parts.iter().map(|p| unescape(p.strip_prefix("_$").map_or(p, |_| &p[1..]))).collect();
    parts.join("::")
}

// `crate::ident` of a v0 symbol: the crate named after the hash (`Cs<hash>_<len><name>`) and the
// identifier that ends the symbol (`<len>[_]<ident>`)
fn demangle_v0_last(sym: &str) -> Option<String> {
    let b = sym.as_bytes();
    let ident = (2..b.len()).find_map(|i| {
        if i > 0 && b[i - 1].is_ascii_digit() || !b[i].is_ascii_digit() {
            return None;
        }
        let end = (i..b.len()).find(|&j| !b[j].is_ascii_digit())?;
        let len: usize = sym[i..end].parse().ok()?;
        let start = end + (b.get(end) == Some(&b'_')) as usize;
        (start + len == b.len() && len > 0).then(|| &sym[start..])
    })?;
    let krate = sym.find("Cs").and_then(|c| {
        let r = &sym[c + 2..];
        let r = &r[r.find('_')? + 1..];
        let end = r.find(|ch: char| !ch.is_ascii_digit())?;
        let len: usize = r[..end].parse().ok()?;
        r.get(end..end + len)
    });
    Some(krate.map_or_else(|| ident.to_string(), |k| format!("{k}::{ident}")))
}

fn unescape(p: &str) -> String {
    const ESC: [(&str, &str); 16] = [
        ("$LT$", "<"), ("$GT$", ">"), ("$C$", ","), ("$u20$", " "), ("$RF$", "&"), ("$BP$", "*"), ("$SP$", "@"),
        ("$LP$", "("), ("$RP$", ")"), ("$u7b$", "{"), ("$u7d$", "}"), ("$u5b$", "["), ("$u5d$", "]"), ("$u27$", "'"),
        ("$u3b$", ";"), ("$u21$", "!"),
    ];
    let mut s = p.replace("..", "::");
    for (k, v) in ESC {
        s = s.replace(k, v);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn demangles_legacy_names() {
        assert_eq!(demangle("_ZN7ddastep6motion6engine19Engine$LT$_$C$_$GT$4tick17h2546dee6a00bc47dE"), "ddastep::motion::engine::Engine<_,_>::tick");
        assert_eq!(demangle("TIM2"), "TIM2");
        assert_eq!(demangle("_ZN4core3ptr13drop_in_place17h0123456789abcdefE"), "core::ptr::drop_in_place");
        assert_eq!(demangle("_RNvNtNtCseL1MqMlhvy0_17compiler_builtins5float3div8___divsf3"), "compiler_builtins::__divsf3");
        assert_eq!(demangle("_RNvNtNtCseL1MqMlhvy0_17compiler_builtins5float3mul8___mulsf3"), "compiler_builtins::__mulsf3");
    }
}

/// Inclusive thread-mode cycles of calls to chosen functions: a call opens when a block starts
/// at one of the entry addresses (in thread mode) and closes when a block starts at its return
/// address (the LR at entry) with the stack pointer back where it was. Cycles of interrupts
/// taken meanwhile are not counted (only thread-mode blocks advance `Mcu::thread_cycles`).
#[derive(Clone, Debug, Default)]
pub struct FnTimer {
    /// Entry addresses of the timed functions, with an index naming each.
    pub targets: Vec<(u32, usize)>,
    /// Open calls: (return address, stack pointer at entry, target index, thread cycles then).
    pub open: Vec<(u32, u32, usize, u64)>,
    /// Finished calls: (target index, inclusive thread-mode cycles, machine cycle at return).
    pub done: Vec<(usize, u64, u64)>,
    /// Finished calls by call site: (target index, return address) → (calls, inclusive cycles).
    pub sites: HashMap<(usize, u32), (u64, u64)>,
    /// Thread-mode blocks run while a timed call was open (exception 0): where the timed
    /// calls' cycles go, per function with `by_function`.
    pub inside: Histogram,
}

/// Where the engine's moves end: every entry of the step half's `finish` (the running move
/// made its last step), with the cycle and whether the step interrupt (TIM2) ran it. In DMA
/// burst mode the fill interrupt runs it, ahead of the pins. For the slave deviation per move.
#[derive(Clone, Debug, Default)]
pub struct MoveMarks {
    /// Entry addresses of `finish`.
    pub targets: Vec<u32>,
    /// (cycle of the entry, run by TIM2's handler), in order.
    pub hits: Vec<(u64, bool)>,
}
