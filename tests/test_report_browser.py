"""The HTML report opened in a real browser: headless Chromium (Debian's ``chromium`` and
``chromium-driver``) driven by Selenium.

Checks that every picture decodes, that the console stays free of errors, that the overlay switch
and the library filters work, and keeps 1280 px wide screenshots in ``test-artifacts/`` (and the
test's tmp folder). Skipped, saying why, when Selenium, the browser or its driver is missing.
"""
from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from seamless_usd.report.html import write_html
from seamless_usd.report.index import write_library_html
from seamless_usd.report.model import Report, StackReport, StackStatus
from specimen import specimen_stack

ROOT = Path(__file__).resolve().parents[1]
ARTIFACTS = ROOT / "test-artifacts"
BROWSERS = ("chromium", "chromium-browser", "google-chrome", "chrome")
DRIVERS = ("chromedriver",)
DRIVER_PATHS = ("/usr/bin/chromedriver", "/usr/lib/chromium/chromedriver")


def _find(names, extra=()) -> str | None:
    for n in names:
        found = shutil.which(n)
        if found:
            return found
    return next((p for p in extra if os.access(p, os.X_OK)), None)


@pytest.fixture(scope="module")
def browser():
    webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed (pip install selenium)")
    binary = os.environ.get("SEAMLESS_USD_CHROMIUM") or _find(BROWSERS)
    driver_path = os.environ.get("SEAMLESS_USD_CHROMEDRIVER") or _find(DRIVERS, DRIVER_PATHS)
    if not binary:
        pytest.skip("no Chromium browser found (apt-get install chromium chromium-driver)")
    if not driver_path:
        pytest.skip("no chromedriver found (apt-get install chromium-driver)")
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = binary
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--window-size=1280,900", "--hide-scrollbars", "--force-device-scale-factor=1"):
        options.add_argument(arg)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    try:
        driver = webdriver.Chrome(service=Service(executable_path=driver_path), options=options)
    except Exception as exc:  # a browser that does not start here is a skip, with the reason
        pytest.skip(f"Chromium did not start: {str(exc).splitlines()[0]}")
    driver.set_page_load_timeout(60)
    yield driver
    driver.quit()


@pytest.fixture(scope="module")
def pages(tmp_path_factory):
    """A single-file report (passing 3-map brick stack, a magnified ORM stack) and a library run."""
    folder = tmp_path_factory.mktemp("browser")
    brick = specimen_stack(ROOT / "sample_assets/brick/scene.usda", "periodic")
    orm = specimen_stack(ROOT / "sample_assets/orm/scene.usda", "magnified")
    single = Report(sources=[brick.source], stacks=[brick, orm], tool_version="test")
    left = StackReport(id="Decal-0", material="</World/Looks/Decal>", source=str(ROOT / "sample_assets/brick/scene.usda"),
                       status=StackStatus.LEFT_ALONE, intent="uv-atlas", intent_reason="UVs 0.11-0.89, 37 islands")
    failed = StackReport(id="Broken-0", material="</World/Looks/Broken>", source=orm.source, status=StackStatus.FAILED,
                         message="@missing.png@: unresolved texture")
    library = Report(sources=[brick.source, orm.source], stacks=[brick, left, orm, failed], tool_version="test")
    return {
        "statuses": sorted(s.status.value for s in library.stacks),
        "single": write_html(single, folder / "report.html"),
        "library": write_library_html(library, folder / "library.html"),
    }


def _open(driver, path: Path, wait_images: bool = True):
    driver.get(path.as_uri())
    driver.get_log("browser")  # nothing from earlier pages
    driver.refresh()
    if wait_images:
        from selenium.webdriver.support.ui import WebDriverWait

        WebDriverWait(driver, 30).until(
            lambda d: d.execute_script("return Array.from(document.images).every(i => i.complete)"))


def _errors(driver) -> list[str]:
    return [e["message"] for e in driver.get_log("browser") if e.get("level") == "SEVERE"]


def _screenshot(driver, name: str, tmp_path: Path) -> Path:
    height = driver.execute_script("return document.documentElement.scrollHeight")
    driver.set_window_size(1280, min(max(int(height) + 40, 600), 12000))
    width = driver.execute_script("return document.documentElement.clientWidth")
    ARTIFACTS.mkdir(exist_ok=True)
    shot = tmp_path / name
    driver.save_screenshot(str(shot))
    shutil.copy(shot, ARTIFACTS / name)
    driver.set_window_size(1280, 900)
    assert width >= 1200, f"viewport {width} px wide, expected about 1280"
    return shot


def _check_images(driver) -> int:
    sizes = driver.execute_script(
        "return Array.from(document.images).map(i => [i.alt, i.naturalWidth, i.naturalHeight])")
    broken = [alt for alt, w, h in sizes if not (w > 0 and h > 0)]
    assert not broken, f"pictures that do not decode: {broken}"
    return len(sizes)


def test_single_report_in_chromium(browser, pages, tmp_path):
    _open(browser, pages["single"])
    count = _check_images(browser)
    assert count == 2 * (3 + 1) + 2 * (2 + 1)  # source and tile: brick's 3 maps + lit, ORM's 2 maps + lit
    assert _errors(browser) == []
    # Nothing wider than the 1280 px window: no horizontal scrolling.
    assert browser.execute_script("return document.documentElement.scrollWidth") <= 1280
    # The overlay is off, then on with the switch, over every same-scale picture.
    overlays = browser.find_elements("css selector", "svg.overlay")
    assert overlays and not any(o.is_displayed() for o in overlays)
    browser.find_element("css selector", "label[for=overlay-toggle]").click()
    assert all(o.is_displayed() for o in overlays)
    shot = _screenshot(browser, "report-1280.png", tmp_path)
    assert shot.stat().st_size > 10_000
    # Verdicts in words are on the page next to the numbers.
    text = browser.find_element("tag name", "body").text
    assert "scale kept (" in text and "magnified or blurred (" in text
    assert _errors(browser) == []


def test_library_index_in_chromium(browser, pages, tmp_path):
    _open(browser, pages["library"])
    assert _check_images(browser) == 2  # one thumbnail per processed stack
    assert _errors(browser) == []

    def visible() -> list[str]:
        return [c.get_attribute("data-status") for c in browser.find_elements("css selector", ".card") if c.is_displayed()]

    assert sorted(visible()) == pages["statuses"]
    browser.find_element("css selector", "label[for=f-left-alone]").click()
    assert visible() == ["left-alone"]
    assert "uv-atlas: UVs 0.11-0.89, 37 islands" in browser.find_element("css selector", ".card.s-left-alone").text
    browser.find_element("css selector", "label[for=f-failed]").click()
    assert visible() == ["failed"]
    browser.find_element("css selector", "label[for=f-all]").click()
    assert len(visible()) == 4
    _screenshot(browser, "library-1280.png", tmp_path)
    # A card's link opens the stack on its file's page, whose pictures decode too.
    browser.find_element("css selector", ".card a.mat").click()
    assert browser.current_url.split("#")[1]
    _check_images(browser)
    assert _errors(browser) == []
