//! `isoforge info`: what a model is before meshing it: its region (and where the region
//! came from), how large its graph and tape are, and its parameters.

use std::process::ExitCode;

use std::io::Write;

use anyhow::{Context as _, Result};
use clap::Args;
use isoforge_field::{Bounds, Context, Tape};
use isoforge_script::Param;
use serde_json::json;

use crate::common::{Global, ModelArgs, print_json};

/// Arguments of `isoforge info`.
#[derive(Args, Debug)]
pub struct InfoArgs {
    #[command(flatten)]
    model: ModelArgs,
}

/// Runs the command.
pub fn run(args: InfoArgs, global: &Global) -> Result<ExitCode> {
    let loaded = args.model.load()?;
    let shape = &loaded.model.shape;
    let source = if args.model.bounds.is_some() {
        "command line"
    } else if loaded.model.bounds.is_some() {
        "script"
    } else {
        "found"
    };
    // Unique nodes after hash-consing, which is what the evaluators see.
    let mut ctx = Context::new();
    ctx.import(shape);
    let nodes = ctx.len();
    let tape_length = Tape::new(shape).len();
    let b = loaded.bounds;
    if global.json {
        print_json(&json!({
            "model": args.model.model.display().to_string(),
            "bounds": [b.min, b.max],
            "bounds_source": source,
            "nodes": nodes,
            "tape_length": tape_length,
            "params": loaded.model.params.iter().map(param_json).collect::<Vec<_>>(),
        }));
    } else if !global.quiet {
        let mut text = format!("model    {}\n", args.model.model.display());
        text += &format!(
            "bounds   {} ({})\n",
            describe_bounds(&b),
            describe_source(source)
        );
        text += &format!("nodes    {nodes} (unique, after merging shared subexpressions)\n");
        text += &format!("tape     {tape_length} instructions\n");
        if loaded.model.params.is_empty() {
            text += "params   none\n";
        }
        for p in &loaded.model.params {
            text += &format!("param    {}\n", describe_param(p));
        }
        // A closed pipe (`isoforge info m.rhai | head -1`) is not an error worth a panic.
        let mut out = std::io::stdout().lock();
        if let Err(e) = out.write_all(text.as_bytes()).and_then(|_| out.flush())
            && e.kind() != std::io::ErrorKind::BrokenPipe
        {
            return Err(e).context("cannot write to stdout");
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn describe_source(source: &str) -> &'static str {
    match source {
        "command line" => "from --bounds",
        "script" => "declared by the script",
        _ => "found by interval pruning",
    }
}

fn describe_bounds(b: &Bounds) -> String {
    let s = b.size();
    format!(
        "[{}, {}, {}] to [{}, {}, {}], {} x {} x {} mm",
        num(b.min[0]),
        num(b.min[1]),
        num(b.min[2]),
        num(b.max[0]),
        num(b.max[1]),
        num(b.max[2]),
        num(s[0]),
        num(s[1]),
        num(s[2])
    )
}

/// A number for people: at most four decimals, no trailing zeros.
fn num(v: f64) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

fn describe_param(p: &Param) -> String {
    let mut s = format!("{} = {} (default {}", p.name, num(p.value), num(p.default));
    if let Some((lo, hi)) = p.range {
        s.push_str(&format!(", range {} to {}", num(lo), num(hi)));
    }
    s.push(')');
    s
}

fn param_json(p: &Param) -> serde_json::Value {
    json!({
        "name": p.name,
        "value": p.value,
        "default": p.default,
        "min": p.range.map(|r| r.0),
        "max": p.range.map(|r| r.1),
    })
}
