#!/usr/bin/python3
"""End-to-end check of `hsr compare`: runs the quick study, validates results.json against
docs/compare-results.schema.json, checks every run against its guarantee, and opens the report
in headless Chromium: every image loaded, every chart drawn, no console message, a screenshot.
Usage: report_check.py HSR_CLI SOURCE_DIR OUT_DIR"""
import json
import pathlib
import re
import shutil
import signal
import subprocess
import sys
import time

import jsonschema


def fail(message):
    print("report_check: " + message, file=sys.stderr)
    sys.exit(1)


def run_study(hsr, out):
    done = subprocess.run([hsr, "compare", "--quick", "--quiet", "--out", str(out)], capture_output=True, text=True)
    if done.returncode != 0:
        fail(f"hsr compare exited {done.returncode}: {done.stderr.strip()}")
    if "Report:" not in done.stdout:
        fail("hsr compare printed no report path")


def check_results(source, out):
    results = json.loads((out / "results.json").read_text())
    schema = json.loads((source / "docs" / "compare-results.schema.json").read_text())
    jsonschema.validate(results, schema)
    if not results["complete"]:
        fail("the quick study is marked incomplete")
    runs = [r for c in results["cases"] for r in c["runs"]]
    algorithms = {r["algorithm"] for r in runs}
    listed = subprocess.run([sys.argv[1], "algorithms", "--json"], capture_output=True, text=True, check=True)
    registered = {a["name"] for a in json.loads(listed.stdout)}
    if algorithms != registered:
        fail(f"the study ran {sorted(algorithms)}, the registry has {sorted(registered)}")
    violations = [(c["scene"], r["variant"], r["check"]) for c in results["cases"] for r in c["runs"]
                  if "VIOLATES" in r.get("check", "") or "declared to fail here, but exact" in r.get("check", "")]
    if violations:
        fail(f"runs against their guarantee: {violations}")
    for c in results["cases"]:
        for r in c["runs"]:
            for image in r.get("images", {}).values():
                if not (out / image).is_file():
                    fail(f"missing picture {image}")
    verdicts = {c["verdict"] for c in results["claims"]}
    if not verdicts or len(results["claims"]) < 10:
        fail("too few claims evaluated")
    return results


def check_in_browser(out):
    page = (out / "index.html").resolve().as_uri()
    chromium = ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--enable-logging=stderr", "--v=0",
                "--virtual-time-budget=10000"]
    dom = subprocess.run(chromium + ["--dump-dom", page], capture_output=True, text=True, timeout=180)
    body = re.search(r"<body([^>]*)>", dom.stdout)
    if not body:
        fail("chromium returned no page")
    attrs = dict(re.findall(r'data-([a-z]+)="([^"]*)"', body.group(1)))
    if "errors" in attrs:
        fail(f"the page reported errors: {attrs['errors']}")
    console = [line for line in dom.stderr.splitlines() if ":CONSOLE" in line]
    if console:
        fail(f"console messages: {console[:5]}")
    loaded, total = (int(x) for x in attrs.get("images", "0/0").split("/"))
    if total == 0 or loaded != total:
        fail(f"images loaded {loaded} of {total}")
    if int(attrs.get("charts", "0")) < 8:
        fail(f"only {attrs.get('charts', '0')} charts drawn")
    shot = out / "screenshot.png"
    subprocess.run(chromium + ["--window-size=1400,4000", f"--screenshot={shot}", page], capture_output=True,
                   timeout=180)
    if not shot.is_file() or shot.stat().st_size < 10000:
        fail("no screenshot")
    print(f"report_check: {loaded} images, {attrs['charts']} charts, no console messages; screenshot {shot}")


def check_interrupt(hsr, source, out):
    """Ctrl-C stops the study after the current run: exit 130, a valid partial report."""
    study = subprocess.Popen([hsr, "compare", "--quick", "--quiet", "--out", str(out)], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not (out / "results.json").is_file() and study.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)  # the first case written
    study.send_signal(signal.SIGINT)
    stdout, stderr = study.communicate(timeout=300)
    if study.returncode != 130:
        fail(f"interrupted study exited {study.returncode} (expected 130): {stderr.strip()}")
    results = json.loads((out / "results.json").read_text())
    jsonschema.validate(results, json.loads((source / "docs" / "compare-results.schema.json").read_text()))
    if results["complete"] or not results["cases"]:
        fail("the interrupted study's results are not a partial report")
    if "partial" not in (out / "index.html").read_text():
        fail("the interrupted study's report does not say it is partial")


def main():
    hsr, source, out = sys.argv[1], pathlib.Path(sys.argv[2]), pathlib.Path(sys.argv[3])
    shutil.rmtree(out, ignore_errors=True)
    check_interrupt(hsr, source, out / "interrupted")
    run_study(hsr, out)
    check_results(source, out)
    check_in_browser(out)


if __name__ == "__main__":
    main()
