//! `lt report`'s page in a real browser: a results folder with two made-up studies (charts from
//! `plot::write_chart`, a table, a Markdown summary, a gallery from `gallery::write_gallery`) is
//! written to a temporary folder, `report::write_report` makes `index.html`, and Debian's
//! Chromium loads it headless and dumps the DOM. The page's own self-check (`#lt-selfcheck`)
//! says how many window errors, unhandled rejections and `console.error` calls it saw, how many
//! images the page has and how many did not decode (naturalWidth 0). The page passes with no
//! errors, every image decoded, and exactly the images the manifests call for; loaded as
//! `index.html#exercise` the galleries' controls are all driven once (every item selected, wipe,
//! flip, crop moved) with the same result.
//!
//! The check can fail: the same page with one chart's SVG deleted must show one broken image,
//! and with a planted `console.error`, a throw and an unhandled rejection must count three errors.
//!
//! Without Chromium (`/usr/bin/chromium`, or `LT_CHROMIUM`) the test says so loudly and passes,
//! unless `LT_REQUIRE_BROWSER=1`, as CI sets it, when it fails.

use lt_estimators::Image;
use lt_experiments::gallery::{write_gallery, Entry};
use lt_experiments::manifest::{Figure, Manifest, Table};
use lt_experiments::plot::{write_chart, Chart, Series, Style};
use lt_experiments::report::{images_in_page, images_when_opened, write_report, SELFCHECK_ID};
use lt_experiments::study::equal_time::{thumb, write_thumb, GALLERIES_CSV};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn chromium() -> Option<PathBuf> {
    let path = std::env::var_os("LT_CHROMIUM")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/usr/bin/chromium"));
    path.is_file().then_some(path)
}

fn fresh_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lt-report-browser-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A convergence-like study: two charts (log-log with a fit and error bars, linear), a table,
/// a summary with a heading, a list, a table and code.
fn convergence(results: &Path) -> Manifest {
    let dir = results.join("convergence");
    std::fs::create_dir_all(&dir).unwrap();
    let spp: Vec<f64> = (0..7).map(|i| 2f64.powi(i)).collect();
    let measured = |name: &str, c: f64| Series {
        name: name.into(),
        points: spp.iter().map(|&n| (n, c / n)).collect(),
        y_interval: spp.iter().map(|&n| (0.8 * c / n, 1.25 * c / n)).collect(),
        style: Style::Measured,
    };
    let mse = Chart {
        title: "cornell-box: MSE against spp".into(),
        x_label: "samples per pixel".into(),
        y_label: "MSE".into(),
        log_x: true,
        log_y: true,
        series: vec![
            measured("pt", 0.1),
            Series {
                name: "pt fit, slope −1.00".into(),
                points: vec![(1.0, 0.1), (64.0, 0.1 / 64.0)],
                y_interval: vec![],
                style: Style::Fitted,
            },
            measured("bdpt", 0.04),
        ],
    };
    let time = Chart {
        title: "relMSE against time".into(),
        x_label: "seconds".into(),
        y_label: "relMSE".into(),
        log_x: false,
        log_y: false,
        series: vec![measured("pt", 0.3)],
    };
    let mut m = Manifest::new("convergence", "Convergence", "test");
    for (stem, chart) in [("mse_spp", &mse), ("relmse_time", &time)] {
        write_chart(&dir.join(stem), chart).unwrap();
        m.figures.push(Figure {
            title: chart.title.clone(),
            caption: "made up for the browser test".into(),
            svg: format!("{stem}.svg"),
            png: format!("{stem}.png"),
        });
    }
    let columns = vec!["integrator".to_string(), "slope".into(), "1/(MSE·s)".into()];
    let rows = vec![
        vec!["pt".to_string(), "−1.00 ± 0.02".into(), "125.0".into()],
        vec!["bdpt".to_string(), "−0.99 ± 0.03".into(), "310.5".into()],
    ];
    let csv: String = std::iter::once(&columns)
        .chain(&rows)
        .map(|r| r.join(",") + "\n")
        .collect();
    std::fs::write(dir.join("efficiency.csv"), csv).unwrap();
    m.tables.push(Table {
        title: "Efficiency".into(),
        caption: "1/(MSE·time)".into(),
        csv: "efficiency.csv".into(),
        columns,
        rows,
    });
    std::fs::write(
        dir.join("summary.md"),
        "# Convergence\n\nUnbiased estimators converge at slope **−1**.\n\n- pt\n- bdpt\n\n\
         | scene | slope |\n|---|--:|\n| cornell-box | −1.00 |\n\n```sh\nlt study convergence\n```\n\n\
         See [the CSV](efficiency.csv).\n",
    )
    .unwrap();
    m.summary = "summary.md".into();
    m.write(&dir).unwrap();
    m
}

/// An equal-time-like study: a shown gallery (reference + three estimates, a crop), no summary,
/// and the compact table of two scenes (`report::overview`): `box`, whose full-size gallery
/// exists (its row opens it), and `door`, whose gallery is named but not there (its row says
/// how to make it).
fn equal_time(results: &Path) -> Manifest {
    let dir = results.join("equal-time");
    let (w, h) = (64, 48);
    let reference = Image::from_fn(w, h, |x, y| {
        let lit = if (24..40).contains(&x) && y < 8 {
            4.0
        } else {
            0.0
        };
        [
            0.2 + 0.4 * x as f64 / w as f64 + lit,
            0.3,
            0.1 + 0.5 * y as f64 / h as f64,
        ]
    });
    let noisy = |amp: f64, seed: u64| {
        let mut s = seed;
        let mut img = reference.clone();
        for p in &mut img.data {
            for c in p.iter_mut() {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                *c = (*c + amp * ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5)).max(0.0);
            }
        }
        img
    };
    let estimates = [noisy(0.4, 1), noisy(0.2, 2), noisy(0.05, 3)];
    let names = ["pt", "bdpt", "vcm"];
    let gallery = |stem: &dyn Fn(&str) -> String, title: &str| {
        let items: Vec<Entry> = estimates
            .iter()
            .zip(names)
            .map(|(img, name)| Entry {
                label: name,
                note: format!("{name}: 10 s"),
                image: img,
                stem: stem(name),
            })
            .collect();
        write_gallery(
            &dir,
            title,
            "10 s each",
            &Entry {
                label: "reference",
                note: "bdpt, 4096 spp".into(),
                image: &reference,
                stem: stem("reference"),
            },
            &items,
            Some(12),
        )
        .unwrap()
    };
    let mut m = Manifest::new("equal-time", "Equal time", "test");
    m.galleries.push(gallery(
        &|n| format!("mis/{n}"),
        "cornell-box at equal time",
    ));
    // The compact table: its CSV, thumbnails, and the scenes' on-demand galleries.
    let mut csv =
        String::from("scene,comparison,integrator,passes,CPU s,budget CPU s,wall s,MSE\n");
    for scene in ["box", "door"] {
        for (k, name) in names.iter().enumerate() {
            csv.push_str(&format!(
                "{scene},equal time,{name},{},1.0,1.1,2.0,0.0{k}1\n",
                16 >> k
            ));
        }
        let g = gallery(
            &|n| {
                format!(
                    "gallery/{scene}/{}",
                    if n == "reference" {
                        n.to_string()
                    } else {
                        format!("time-{n}")
                    }
                )
            },
            &format!("{scene}, equal time"),
        );
        for i in std::iter::once(&g.reference).chain(&g.items) {
            let what = Path::new(&i.image).file_stem().unwrap().to_str().unwrap();
            let rgb = image::open(dir.join(&i.image)).unwrap().into_rgb8();
            write_thumb(&dir.join(thumb(scene, what)), &rgb).unwrap();
        }
        m.galleries.push(g);
    }
    std::fs::remove_dir_all(dir.join("gallery/door")).unwrap();
    std::fs::write(dir.join(GALLERIES_CSV), csv).unwrap();
    m.tables.push(Table {
        title: "Equal samples and equal time".into(),
        caption: String::new(),
        csv: GALLERIES_CSV.into(),
        columns: vec![],
        rows: vec![],
    });
    m.write(&dir).unwrap();
    m
}

/// `<img` tags in the page as loaded: those inside a `<template>` (a row's on-demand
/// galleries) are not.
fn img_tags_shown(html: &str) -> usize {
    let mut n = 0;
    let mut rest = html;
    while let Some(t) = rest.find("<template") {
        n += rest[..t].matches("<img ").count();
        rest = &rest[t + rest[t..].find("</template>").unwrap()..];
    }
    n + rest.matches("<img ").count()
}

/// Chromium's DOM of `url` after the page settled, or None when there is no browser.
fn dump_dom(url: &str, profile: &Path) -> Option<String> {
    let browser = chromium()?;
    let mut child = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--virtual-time-budget=10000",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(["--dump-dom", url])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("chromium starts");
    // Read stdout on a thread so a large DOM cannot block the browser; give up after 2 minutes.
    let mut stdout = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        std::io::Read::read_to_string(&mut stdout, &mut s).map(|_| s)
    });
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let dom = reader.join().unwrap().expect("chromium's output is UTF-8");
            if !status.success() {
                let mut err = String::new();
                if let Some(mut e) = child.stderr.take() {
                    let _ = std::io::Read::read_to_string(&mut e, &mut err);
                }
                panic!("chromium failed ({status}) on {url}:\n{err}");
            }
            return Some(dom);
        }
        if start.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            panic!("chromium did not finish {url} in 120 s");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// The self-check's record from a dumped DOM.
#[derive(Debug)]
struct Check {
    json: String,
    done: bool,
    errors: u64,
    images: u64,
    broken: u64,
}

fn selfcheck(dom: &str) -> Check {
    let open = format!("<pre id=\"{SELFCHECK_ID}\" hidden=\"\">");
    let start = dom
        .find(&open)
        .map(|i| i + open.len())
        .unwrap_or_else(|| panic!("no {open} in the dumped DOM:\n{dom}"));
    let end = start + dom[start..].find("</pre>").expect("</pre>");
    let json = dom[start..end]
        .replace("&quot;", "\"")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&");
    let number = |key: &str| -> u64 {
        let k = format!("\"{key}\":");
        let i = json
            .find(&k)
            .unwrap_or_else(|| panic!("self-check has no {key}: {json}"))
            + k.len();
        json[i..]
            .chars()
            .take_while(|c| c.is_ascii_digit())
            .collect::<String>()
            .parse()
            .unwrap_or_else(|_| panic!("self-check's {key} is no count: {json}"))
    };
    Check {
        done: json.contains("\"done\":true"),
        errors: number("errors"),
        images: number("images"),
        broken: number("broken"),
        json,
    }
}

fn file_url(path: &Path, fragment: &str) -> String {
    let abs = std::fs::canonicalize(path).unwrap();
    format!("file://{}{fragment}", abs.display())
}

#[test]
fn report_page_loads_cleanly_in_chromium_and_the_check_can_fail() {
    let results = fresh_dir("results");
    let manifests = [convergence(&results), equal_time(&results)];
    let index = write_report(&results).unwrap();
    assert_eq!(index, results.join("index.html"));
    let html = std::fs::read_to_string(&index).unwrap();
    // Study order, relative links, no network.
    let (c, e) = (
        html.find("id=\"study-convergence\"").unwrap(),
        html.find("id=\"study-equal-time\"").unwrap(),
    );
    assert!(c < e, "convergence comes before equal-time");
    assert!(html.contains("src=\"convergence/mse_spp.svg\""));
    assert!(html.contains("href=\"convergence/efficiency.csv\""));
    assert!(!html.contains("http://") && !html.contains("https://"));
    let dir = |m: &Manifest| results.join(&m.study);
    let expected: usize = manifests.iter().map(|m| images_in_page(m, &dir(m))).sum();
    // Two charts, the shown gallery, the compact table's 2 × (1 + 3) thumbnails.
    assert_eq!(expected, 2 + (5 + 3) + 2 * (1 + 3));
    assert_eq!(img_tags_shown(&html), expected);
    // Opening every row adds box's gallery; door's images are not there.
    let opened: usize = manifests
        .iter()
        .map(|m| images_when_opened(m, &dir(m)))
        .sum();
    assert_eq!(opened, 5 + 3);
    assert!(html.contains("lt study equal-time --scale test --scene door"));

    if chromium().is_none() {
        let msg = "\n\n!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!\n\
                   !! report_browser: Chromium not found (/usr/bin/chromium or LT_CHROMIUM):\n\
                   !! the report page was NOT checked in a browser. apt-get install chromium\n\
                   !!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!!\n";
        // Straight to the process's stderr: the test harness captures eprintln!, and this
        // must be seen even when the test passes.
        let _ = std::io::Write::write_all(&mut std::io::stderr(), msg.as_bytes());
        assert!(
            std::env::var("LT_REQUIRE_BROWSER").as_deref() != Ok("1"),
            "LT_REQUIRE_BROWSER=1 but Chromium is not installed"
        );
        std::fs::remove_dir_all(&results).unwrap();
        return;
    }

    let profile = fresh_dir("profile");
    // The page as written, then with every gallery control driven once.
    for fragment in ["", "#exercise"] {
        let dom = dump_dom(&file_url(&index, fragment), &profile).unwrap();
        let check = selfcheck(&dom);
        assert!(check.done, "self-check did not finish: {}", check.json);
        assert_eq!(
            check.errors, 0,
            "errors on the page{fragment}: {}",
            check.json
        );
        assert_eq!(
            check.broken, 0,
            "images that did not decode{fragment}: {}",
            check.json
        );
        let shown = if fragment == "#exercise" {
            expected + opened
        } else {
            expected
        };
        assert_eq!(check.images as usize, shown, "{}", check.json);
        if fragment == "#exercise" {
            assert!(
                dom.contains("data-exercised=\"1\""),
                "the exercise did not run"
            );
            // box's row opened its gallery, door's says how to make it.
            // (Counted on the rows: the page's CSS names the state too.)
            let rows = |state: &str| {
                dom.matches(&format!("<tr class=\"detail\" data-state=\"{state}\">"))
                    .count()
            };
            assert_eq!((rows("shown"), rows("absent")), (1, 1), "{dom}");
        }
    }

    // A missing image is caught: delete one chart's SVG (shown by exactly one <img>).
    let missing = fresh_dir("missing");
    copy_tree(&results, &missing);
    std::fs::remove_file(missing.join("convergence/relmse_time.svg")).unwrap();
    let index2 = write_report(&missing).unwrap();
    let check = selfcheck(&dump_dom(&file_url(&index2, ""), &profile).unwrap());
    assert!(check.done, "{}", check.json);
    assert_eq!(check.broken, 1, "{}", check.json);
    assert!(
        check.json.contains("convergence/relmse_time.svg"),
        "{}",
        check.json
    );
    assert_eq!(check.errors, 0, "{}", check.json);

    // Script errors are caught: a console.error, an uncaught throw and an unhandled rejection.
    let planted = "<script>console.error('planted console.error');\
                   Promise.reject(new Error('planted rejection'));\
                   throw new Error('planted throw');</script></body>";
    let bad = html.replacen("</body>", planted, 1);
    let bad_index = results.join("bad.html");
    std::fs::write(&bad_index, bad).unwrap();
    let check = selfcheck(&dump_dom(&file_url(&bad_index, ""), &profile).unwrap());
    assert!(check.done, "{}", check.json);
    assert_eq!(check.errors, 3, "{}", check.json);
    for word in [
        "planted console.error",
        "planted rejection",
        "planted throw",
    ] {
        assert!(
            check.json.contains(word),
            "{word} not recorded: {}",
            check.json
        );
    }
    assert_eq!(check.broken, 0, "{}", check.json);

    for d in [&results, &missing, &profile] {
        let _ = std::fs::remove_dir_all(d);
    }
}

fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_tree(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).unwrap();
        }
    }
}
