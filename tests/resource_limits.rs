//! Claim: an absurd request is refused before anything is allocated, with the limit named and
//! the option that lifts it; lifting it works; and a scene or image that cannot fit in memory
//! fails cleanly (exit 2, one line) instead of aborting.
//!
//! What belongs here: image size, bounce count, thread count, sample count, filter radius,
//! picture zoom and memory limits, through the real binary. Malformed files belong in `bad_input.rs`.

mod common;

use common::{copy_scene, listing, scratch_dir, whitted};

/// True when the kernel grants any allocation (`vm.overcommit_memory = 1`): then a request
/// for more memory than exists succeeds until it is touched, and cannot be tested for.
fn overcommit_always() -> bool {
    std::fs::read_to_string("/proc/sys/vm/overcommit_memory").is_ok_and(|s| s.trim() == "1")
}

#[test]
fn absurd_image_size_is_refused_naming_the_limit_and_the_option() {
    let dir = scratch_dir("limits/size");
    // The scene does not even exist: the size is refused before anything is read.
    let run = whitted(
        &dir,
        &[
            "render",
            "absent.txt",
            "-o",
            "out.png",
            "--size",
            "200000",
            "200000",
        ],
    );
    assert_eq!(
        run.assert_error("image size"),
        "image size 200000x200000 is 40000000000 pixels, over the limit of 67108864 (raise it \
         with --max-pixels N)"
    );
    // The course spelling too.
    let run = whitted(
        &dir,
        &[
            "-input",
            "absent.txt",
            "-size",
            "200000",
            "200000",
            "-output",
            "o.tga",
        ],
    );
    run.assert_error("image size 200000x200000 is 40000000000 pixels");
    let run = whitted(
        &dir,
        &["render", "absent.txt", "-o", "out.png", "--size", "0", "5"],
    );
    run.assert_error("image size 0x5: expected a width and height of at least 1");
    assert!(listing(&dir).is_empty());
}

#[test]
fn an_image_too_large_for_memory_is_an_error_not_an_abort() {
    let dir = scratch_dir("limits/memory");
    // 1.6e19 pixels: more than any address space, with the pixel limit lifted as far as it goes.
    let run = whitted(
        &dir,
        &[
            "render",
            "absent.txt",
            "-o",
            "out.png",
            "--size",
            "4000000000",
            "4000000000",
            "--max-pixels",
            "18446744073709551615",
        ],
    );
    run.assert_error(
        "image size 4000000000x4000000000 needs 228881838989257 MiB, more memory than",
    );
    if overcommit_always() {
        eprintln!("skipped the 100000x100000 case: vm.overcommit_memory = 1 grants any request");
    } else {
        let run = whitted(
            &dir,
            &[
                "render",
                "absent.txt",
                "-o",
                "out.png",
                "--size",
                "100000",
                "100000",
                "--max-pixels",
                "10000000000",
            ],
        );
        run.assert_error("image size 100000x100000 needs 143127 MiB, more memory than");
    }
    assert!(listing(&dir).is_empty());
}

#[test]
fn absurd_bounce_count_is_refused_naming_the_limit_and_the_option() {
    let dir = scratch_dir("limits/bounces");
    let run = whitted(
        &dir,
        &["render", "absent.txt", "-o", "out.png", "--bounces", "5000"],
    );
    assert_eq!(
        run.assert_error("bounce count"),
        "bounce count 5000 is over the limit of 1000 (raise it with --max-bounces N)"
    );
    let run = whitted(
        &dir,
        &[
            "render",
            "absent.txt",
            "-o",
            "o.png",
            "--bounces",
            "99999999999",
        ],
    );
    run.assert_error("option --bounces: expected a bounce count, found `99999999999`");
    assert!(listing(&dir).is_empty());
}

#[test]
fn lifting_the_bounce_limit_works_without_overflowing_the_stack() {
    // Two facing mirrors and no weight cutoff: every pixel that sees a mirror recurses the full
    // 20000 bounces, far deeper than a default 2 MiB thread stack allows.
    let dir = scratch_dir("limits/deep");
    copy_scene("facing_mirrors.txt", &dir);
    let run = whitted(
        &dir,
        &[
            "render",
            "facing_mirrors.txt",
            "-o",
            "out.png",
            "--size",
            "2",
            "2",
            "--weight",
            "0",
            "--bounces",
            "20000",
            "--max-bounces",
            "20000",
        ],
    );
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    assert!(dir.join("out.png").is_file());
}

#[test]
fn absurd_thread_count_is_refused() {
    let dir = scratch_dir("limits/threads");
    let run = whitted(
        &dir,
        &[
            "render",
            "absent.txt",
            "-o",
            "out.png",
            "--threads",
            "100000",
        ],
    );
    assert_eq!(
        run.assert_error("thread count"),
        "thread count 100000 is over the limit of 1024"
    );
}

#[test]
fn a_scene_too_large_for_memory_is_an_error_not_an_abort() {
    if overcommit_always() {
        eprintln!("skipped: vm.overcommit_memory = 1 grants any request");
        return;
    }
    // A sparse file of 4 TiB takes no disk space; reading it must fail cleanly.
    let dir = scratch_dir("limits/huge_scene");
    let file = std::fs::File::create(dir.join("huge.txt")).unwrap();
    file.set_len(1 << 42).unwrap();
    drop(file);
    let run = whitted(&dir, &["render", "huge.txt", "-o", "out.png"]);
    run.assert_error("huge.txt: cannot read scene: out of memory");
    assert_eq!(listing(&dir), ["huge.txt"]);
}

#[test]
fn a_negative_weight_is_refused() {
    let dir = scratch_dir("limits/weight");
    let run = whitted(
        &dir,
        &["render", "absent.txt", "-o", "out.png", "--weight", "-1"],
    );
    assert_eq!(
        run.assert_error("weight"),
        "weight -1: expected a non-negative number (see `whitted render --help`)"
    );
}

#[test]
fn rays_that_multiply_every_bounce_are_refused_before_they_fill_memory() {
    // Four nested spheres, each reflecting and transmitting 0.9, seen from their centre: every
    // ray hits a sphere and spawns both a mirror and a refracted ray, most of which stay inside
    // and hit again, and with --weight 0 nothing prunes them. The rays of a band grow
    // geometrically; the packet tracer stops at its queue limit (bounce 21 here).
    let dir = scratch_dir("limits/multiplying");
    let scene = "PerspectiveCamera { center 0 0 0 direction 0 0 -1 up 0 1 0 angle 60 }
        Lights { numLights 1 DirectionalLight { direction 0 -1 0 color 1 1 1 } }
        Materials { numMaterials 1 PhongMaterial { diffuseColor 0.1 0.1 0.1
            reflectiveColor 0.9 0.9 0.9 transparentColor 0.9 0.9 0.9 indexOfRefraction 1 } }
        Group { numObjects 4 MaterialIndex 0
            Sphere { center 0 0 0 radius 1 } Sphere { center 0 0 0 radius 2 }
            Sphere { center 0 0 0 radius 3 } Sphere { center 0 0 0 radius 4 } }";
    std::fs::write(dir.join("nest.txt"), scene).unwrap();
    let run = whitted(
        &dir,
        &[
            "render",
            "nest.txt",
            "-o",
            "out.png",
            "--size",
            "4",
            "2",
            "--shade-back",
            "--bounces",
            "30",
            "--weight",
            "0",
        ],
    );
    let msg = run.assert_error("the packet tracer would queue");
    assert!(msg.contains("lower --bounces, raise --weight, or render with --tracer reference"));
    assert_eq!(listing(&dir), ["nest.txt"]);
}

#[test]
fn absurd_sample_counts_filter_radii_and_zooms_are_refused_naming_the_limit_and_the_option() {
    let dir = scratch_dir("limits/sampling");
    let base = ["render", "absent.txt", "-o", "out.png"];
    let refused = |extra: &[&str], message: &str| {
        let mut args = base.to_vec();
        args.extend_from_slice(extra);
        assert_eq!(whitted(&dir, &args).assert_error(""), message, "{extra:?}");
    };
    refused(
        &["--samples", "4096"],
        "sample count 4096 is over the limit of 1024 per pixel (raise it with --max-samples N)",
    );
    refused(
        &["--samples", "100", "--max-samples", "64"],
        "sample count 100 is over the limit of 64 per pixel (raise it with --max-samples N)",
    );
    refused(
        &["--filter", "gaussian", "100"],
        "gaussian filter sigma 100 reaches 200 pixels, over the limit of 32 (raise it with \
         --max-filter-radius N)",
    );
    let mut huge = base.to_vec();
    huge.extend(["-box_filter", "1e30"]);
    let msg = whitted(&dir, &huge).assert_error("box filter radius 1");
    assert!(
        msg.ends_with("(raise it with --max-filter-radius N)"),
        "{msg}"
    );
    refused(
        &["--size", "512", "512", "--render-samples", "s.png", "20"],
        "option --render-samples: a 512x512 image zoomed 20 times is 10240x10240 pixels, over \
         the limit of 67108864 (raise it with --max-pixels N)",
    );
    assert!(listing(&dir).is_empty());
    // Lifting the limits works (the scene is missing, so the error is the next check's).
    let mut args = base.to_vec();
    args.extend(["--samples", "2025", "--max-samples", "2048"]);
    args.extend(["--filter", "tent", "40", "--max-filter-radius", "40"]);
    whitted(&dir, &args).assert_error("absent.txt: cannot read scene");
    assert!(listing(&dir).is_empty());
}
