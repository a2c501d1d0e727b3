"""--report DIR (issue 28): one self-contained index.html beside report.md, with the tables, the
premises, every plot embedded, the command, garant's version and the inputs' SHA-256; rendered in
headless Chromium where it is installed."""
import hashlib
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from garant.verify.cli import main

REAL = Path(__file__).resolve().parents[2] / "shared" / "data" / "real"


def _reports(tmp_path):
    data = tmp_path / "a<b>.csv"                             # a file name that must be escaped
    assert main(["simulate", "--model", "two-axis", "--plan", "quarter", "--sigma", "1e-5", "-o", str(data)]) == 0
    assert main(["estimate", "--model", "two-axis", str(data), "--sigma", "1e-5", "--report", str(tmp_path / "e")]) == 0
    log = REAL / "repeat_session2_acc.txt"
    assert main(["calibrate-norm", str(log), "--report", str(tmp_path / "c")]) == 0
    return {"e": data, "c": log}


def test_each_report_is_one_self_contained_page(tmp_path, capsys):
    inputs = _reports(tmp_path)
    capsys.readouterr()
    for name, source in inputs.items():
        folder = tmp_path / name
        html = (folder / "index.html").read_text()
        assert (folder / "report.md").exists()
        pngs = sorted(p.name for p in folder.glob("*.png"))
        assert pngs and html.count('src="data:image/png;base64,') == len(pngs)     # every plot, embedded
        assert not re.search(r"""(src|href)=["'](?!data:)""", html)                 # nothing fetched
        assert "<table>" in html and "Premises" in html and "Reproduce with" in html
        assert hashlib.sha256(source.read_bytes()).hexdigest() in html and "garant 0." in html
        assert "@page{size:A4" in html
    assert "a&lt;b&gt;.csv" in (tmp_path / "e" / "index.html").read_text() and "a<b>" not in (
        tmp_path / "e" / "index.html").read_text()


def _chromium():
    return shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.mark.skipif(not _chromium(), reason="no Chromium here (Debian package chromium): the page is not rendered")
def test_each_report_renders_in_headless_chromium(tmp_path, capsys):
    _reports(tmp_path)
    capsys.readouterr()
    for name in ("e", "c"):
        page = tmp_path / name / "index.html"
        shot = tmp_path / f"{name}.png"
        dom = subprocess.run([_chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--dump-dom",
                              page.as_uri()], capture_output=True, text=True, timeout=120).stdout
        assert "<table>" in dom and dom.count("data:image/png;base64,") >= 1
        subprocess.run([_chromium(), "--headless", "--no-sandbox", "--disable-gpu", f"--screenshot={shot}",
                        "--window-size=1000,3000", page.as_uri()], capture_output=True, timeout=120)
        assert shot.exists() and shot.stat().st_size > 10_000      # something visible was drawn
