"""Screenshots of a report in headless Chromium for the README: the verdict and summary, and one scene.

Usage: python docs/make_screenshots.py REPORT_DIR   (e.g. reports/default after `make report`)
"""
import shutil
import sys
import time
from pathlib import Path

from selenium import webdriver
from selenium.webdriver.common.by import By


def browser():
    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which("chromium")
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--hide-scrollbars",
                "--window-size=1200,900", "--allow-file-access-from-files"):
        options.add_argument(arg)
    return webdriver.Chrome(options=options, service=webdriver.ChromeService(executable_path=shutil.which("chromedriver")))


def main(report: Path, out: Path = Path(__file__).resolve().parent):
    page = browser()
    try:
        page.get((report / "index.html").resolve().as_uri())
        time.sleep(1.0)
        page.save_screenshot(str(out / "report-summary.png"))
        section = page.find_element(By.ID, "scene-buck-dcm")
        page.execute_script("arguments[0].scrollIntoView(true);", section)
        time.sleep(0.5)
        page.save_screenshot(str(out / "report-scene.png"))
    finally:
        page.quit()
    print(f"wrote {out / 'report-summary.png'} and {out / 'report-scene.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1]))
