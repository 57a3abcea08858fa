//! Claim: the render-farm files in `deploy/` work as written: the Slurm array script run once per
//! task with the environment Slurm gives an array task (`SLURM_ARRAY_TASK_ID` and its kin), then
//! its merge script; the Kubernetes Indexed Job's container command run once per index with
//! `JOB_COMPLETION_INDEX` and the manifest's own environment, then the merge Job's command; the
//! Slurm sweep script once per scene. Each gives the bytes of the one-go render.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{copy_scene, our_scenes, scratch_dir};

const WHITTED: &str = env!("CARGO_BIN_EXE_whitted");
const TILES: u32 = 4;
const OPTIONS: &str = "--size 160 120 --shadows --shade-back --bounces 6";

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn showcase() -> PathBuf {
    our_scenes()
        .into_iter()
        .find(|p| p.ends_with("showcase.txt"))
        .unwrap()
}

/// PATH with the built `whitted` first, as an image or module system would provide it.
fn path_with_whitted() -> String {
    let bin = Path::new(WHITTED).parent().unwrap().display().to_string();
    format!("{bin}:{}", std::env::var("PATH").unwrap_or_default())
}

/// Runs `program args` with exactly `env` (plus PATH) in `dir`; panics unless it succeeds.
fn run(dir: &Path, program: &str, args: &[&str], env: &[(&str, String)]) {
    let out = Command::new(program)
        .args(args)
        .current_dir(dir)
        .env_clear()
        .env("PATH", path_with_whitted())
        .envs(env.iter().map(|(k, v)| (*k, v.as_str())))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{program} {args:?} with {env:?} failed:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The one-go render of `scene` with OPTIONS into `out`.
fn one_go(dir: &Path, scene: &Path, out: &str) -> Vec<u8> {
    let mut args = vec!["render".to_string(), scene.display().to_string()];
    args.extend(OPTIONS.split(' ').map(String::from));
    args.extend(["-o".to_string(), out.to_string()]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    run(dir, WHITTED, &args, &[]);
    std::fs::read(dir.join(out)).unwrap()
}

#[test]
fn the_slurm_array_script_and_its_merge_give_the_one_go_render() {
    let dir = scratch_dir("deploy_slurm");
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let common = [
        ("SCENE", showcase().display().to_string()),
        ("OUT_DIR", out.display().to_string()),
        ("TILES", TILES.to_string()),
        ("OPTIONS", OPTIONS.to_string()),
    ];
    for task in 0..TILES {
        // What sbatch --array=0-3 --cpus-per-task=1 sets for each task.
        let mut env = common.to_vec();
        env.extend([
            ("SLURM_ARRAY_TASK_ID", task.to_string()),
            ("SLURM_ARRAY_TASK_COUNT", TILES.to_string()),
            ("SLURM_ARRAY_TASK_MIN", "0".to_string()),
            ("SLURM_ARRAY_TASK_MAX", (TILES - 1).to_string()),
            ("SLURM_ARRAY_JOB_ID", "4242".to_string()),
            ("SLURM_JOB_ID", (4243 + task).to_string()),
            ("SLURM_CPUS_PER_TASK", "1".to_string()),
        ]);
        let script = repo("deploy/slurm/render-tiles.sbatch");
        run(&dir, "bash", &[&script.display().to_string()], &env);
        assert!(out.join(format!("tile-{task}.exr")).is_file());
    }
    let mut env = common.to_vec();
    env.push(("SLURM_JOB_ID", "4300".to_string()));
    let merge = repo("deploy/slurm/merge.sbatch");
    run(&dir, "bash", &[&merge.display().to_string()], &env);
    let merged = std::fs::read(out.join("frame.exr")).unwrap();
    assert!(
        merged == one_go(&dir, &showcase(), "whole.exr"),
        "Slurm tiles differ from one go"
    );
}

/// The lines of the block scalar that follows the line `key` (`args:` then `- |`) in the first
/// container of a manifest, de-indented: the container's shell command.
fn block_after(yaml: &str, key: &str) -> String {
    let lines: Vec<&str> = yaml.lines().collect();
    let at = lines.iter().position(|l| l.trim() == key).expect(key);
    let dash = lines[at + 1];
    assert_eq!(dash.trim(), "- |", "{key} holds one block scalar");
    let indent = lines[at + 2].len() - lines[at + 2].trim_start().len();
    lines[at + 2..]
        .iter()
        .take_while(|l| l.trim().is_empty() || l.len() - l.trim_start().len() >= indent)
        .map(|l| l.get(indent..).unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The `env:` list of a manifest's container: (name, value) pairs.
fn env_of(yaml: &str) -> Vec<(String, String)> {
    let lines: Vec<&str> = yaml.lines().map(str::trim).collect();
    lines
        .windows(2)
        .filter_map(|w| {
            let name = w[0].strip_prefix("- name: ")?;
            let value = w[1].strip_prefix("value: ")?;
            Some((name.to_string(), value.trim_matches('"').to_string()))
        })
        .collect()
}

/// The value of a `key: value` line.
fn field(yaml: &str, key: &str) -> String {
    yaml.lines()
        .find_map(|l| l.trim().strip_prefix(&format!("{key}: ")))
        .unwrap_or_else(|| panic!("no {key}"))
        .to_string()
}

#[test]
fn the_kubernetes_indexed_job_and_its_merge_give_the_one_go_render() {
    let dir = scratch_dir("deploy_kubernetes");
    let data = dir.join("data");
    std::fs::create_dir_all(&data).unwrap();
    // The volume holds the scene as scene.txt, with the meshes it loads.
    let copied = copy_scene("showcase.txt", &data);
    std::fs::rename(copied, data.join("scene.txt")).unwrap();
    let job = std::fs::read_to_string(repo("deploy/kubernetes/render-tiles.yaml")).unwrap();
    assert_eq!(field(&job, "completionMode"), "Indexed");
    let manifest_env = env_of(&job);
    let tiles = &manifest_env.iter().find(|(k, _)| k == "TILES").unwrap().1;
    assert_eq!(
        &field(&job, "completions"),
        tiles,
        "completions and TILES agree"
    );
    let command = block_after(&job, "args:");
    assert!(
        command.contains("--tile \"$JOB_COMPLETION_INDEX/$TILES\""),
        "{command}"
    );
    // The manifest's environment with this machine's paths in place of the volume's /data, and
    // a smaller frame in fewer tiles.
    let env = |extra: &[(&str, String)]| -> Vec<(String, String)> {
        let mut env: Vec<(String, String)> = manifest_env
            .iter()
            .map(|(k, v)| (k.clone(), v.replace("/data", &data.display().to_string())))
            .collect();
        for (k, v) in extra {
            env.retain(|(name, _)| name != k);
            env.push((k.to_string(), v.clone()));
        }
        env
    };
    for index in 0..TILES {
        let env = env(&[
            ("TILES", TILES.to_string()),
            ("OPTIONS", OPTIONS.to_string()),
            ("JOB_COMPLETION_INDEX", index.to_string()),
            ("HOSTNAME", format!("whitted-tiles-{index}-x7k2p")),
        ]);
        let env: Vec<(&str, String)> = env.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
        run(&dir, "/bin/sh", &["-c", &command], &env);
    }
    let merge = std::fs::read_to_string(repo("deploy/kubernetes/merge-job.yaml")).unwrap();
    let merge_env: Vec<(String, String)> = env_of(&merge)
        .into_iter()
        .map(|(k, v)| {
            let v = if k == "TILES" { TILES.to_string() } else { v };
            (k, v.replace("/data", &data.display().to_string()))
        })
        .collect();
    let merge_env: Vec<(&str, String)> = merge_env
        .iter()
        .map(|(k, v)| (k.as_str(), v.clone()))
        .collect();
    run(
        &dir,
        "/bin/sh",
        &["-c", &block_after(&merge, "args:")],
        &merge_env,
    );
    let merged = std::fs::read(data.join("out/frame.exr")).unwrap();
    assert!(
        merged == one_go(&dir, &data.join("scene.txt"), "whole.exr"),
        "Kubernetes tiles differ from one go"
    );
}

#[test]
fn the_slurm_sweep_renders_one_scene_per_task() {
    let dir = scratch_dir("deploy_sweep");
    let scenes: Vec<PathBuf> = our_scenes().into_iter().take(3).collect();
    let list: String = scenes
        .iter()
        .map(|p| format!("{}\n", p.display()))
        .collect();
    std::fs::write(dir.join("scenes.list"), list).unwrap();
    std::fs::create_dir_all(dir.join("out")).unwrap();
    for (task, scene) in scenes.iter().enumerate() {
        let env = [
            ("SCENE_LIST", "scenes.list".to_string()),
            ("OUT_DIR", "out".to_string()),
            ("OPTIONS", OPTIONS.to_string()),
            ("SLURM_ARRAY_TASK_ID", task.to_string()),
            ("SLURM_ARRAY_TASK_COUNT", scenes.len().to_string()),
            ("SLURM_ARRAY_JOB_ID", "77".to_string()),
            ("SLURM_CPUS_PER_TASK", "1".to_string()),
        ];
        let script = repo("deploy/slurm/sweep.sbatch");
        run(&dir, "bash", &[&script.display().to_string()], &env);
        let name = scene.file_stem().unwrap().to_string_lossy();
        let swept = std::fs::read(dir.join(format!("out/{name}.png"))).unwrap();
        assert!(
            swept == one_go(&dir, scene, "one.png"),
            "{name}: sweep differs from one go"
        );
    }
}

#[test]
fn the_gnu_parallel_driver_gives_the_one_go_render() {
    let dir = scratch_dir("deploy_parallel");
    let script = repo("deploy/parallel/render.sh").display().to_string();
    let scene = showcase().display().to_string();
    let mut args = vec![script.as_str(), "4", "frame.png", scene.as_str()];
    args.extend(OPTIONS.split(' '));
    run(&dir, "bash", &args, &[("HOME", dir.display().to_string())]);
    let merged = std::fs::read(dir.join("frame.png")).unwrap();
    assert!(
        merged == one_go(&dir, &showcase(), "whole.png"),
        "parallel tiles differ from one go"
    );
}
