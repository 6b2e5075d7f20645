#!/usr/bin/env python3
"""The experimenter's console in a real browser (headless Chromium through
Selenium): a participant fills in both questionnaires after the condition
they drove; the same form sent twice and an incomplete one are refused on
the page; the database holds exactly one row per answer.

usage: console_browser.py FIXTURE SCRATCH_DIR   (run by ctest)
"""
import sqlite3
import subprocess
import sys

from selenium import webdriver
from selenium.webdriver.chrome.options import Options
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By
from selenium.webdriver.support import expected_conditions
from selenium.webdriver.support.ui import WebDriverWait


def main():
    fixture, scratch = sys.argv[1], sys.argv[2]
    server = subprocess.Popen([fixture, scratch], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        url = server.stdout.readline().split()[1]
        db = server.stdout.readline().split()[1]
        options = Options()
        for argument in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu"):
            options.add_argument(argument)
        browser = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
        browser.set_page_load_timeout(30)
        try:
            run(browser, url)
        finally:
            browser.quit()
        rows = sorted(sqlite3.connect(db).execute(
            "SELECT participant, condition, questionnaire, item, value FROM study_answers").fetchall())
        expected = sorted([
            ("A", "gesture", "thesis", "easy_to_learn", "4"),
            ("A", "gesture", "thesis", "efficient", "5"),
            ("A", "gesture", "thesis", "remarks", "the wall <stopped> my hand"),
            ("A", "gesture", "rating", "rating", "5"),
            ("A", "gesture", "rating", "rating.path", "controllable=yes,adequate=yes,satisfactory=no"),
            ("A", "gesture", "rating", "score", "5"),
        ])
        assert rows == expected, f"rows in the database:\n{rows}\nexpected:\n{expected}"
        print("console_browser: ok,", len(rows), "answer rows")
    finally:
        server.stdin.close()
        server.wait(timeout=30)


def form_url(browser, url, name):
    """The schedule's link to questionnaire `name` for A after gesture."""
    browser.get(url)
    link = browser.find_element(By.LINK_TEXT, name)
    return link.get_attribute("href")


def result(browser):
    """The result page's message: waited for, since a click on submit returns
    before the next page has loaded (the form page has no #result)."""
    element = WebDriverWait(browser, 30).until(
        expected_conditions.presence_of_element_located((By.ID, "result")))
    return element.text


def run(browser, url):
    thesis = form_url(browser, url, "thesis")
    rating = form_url(browser, url, "rating")
    # The cockpit has not been driven: the schedule offers no form for it.
    assert "condition=cockpit" not in thesis + rating

    def fill_thesis():
        browser.get(thesis)
        browser.find_element(By.CSS_SELECTOR, 'input[name="easy_to_learn"][value="4"]').click()
        browser.find_element(By.CSS_SELECTOR, 'input[name="efficient"][value="5"]').click()
        browser.find_element(By.NAME, "remarks").send_keys("the wall <stopped> my hand")
        browser.find_element(By.ID, "submit").click()

    fill_thesis()
    message = result(browser)
    assert "recorded thesis" in message, message
    fill_thesis()  # the same form again
    message = result(browser)
    assert "already answered" in message, message

    browser.get(rating)  # submitted empty: refused, each problem listed
    browser.find_element(By.ID, "submit").click()
    message = result(browser)
    assert "to correct" in message, message
    assert browser.find_elements(By.CSS_SELECTOR, "#errors li")

    browser.get(rating)
    for node, answer in (("controllable", "yes"), ("adequate", "yes"), ("satisfactory", "no")):
        browser.find_element(By.CSS_SELECTOR, f'input[name="rating.node.{node}"][value="{answer}"]').click()
    browser.find_element(By.CSS_SELECTOR, 'input[name="rating"][value="5"]').click()
    browser.find_element(By.ID, "submit").click()
    message = result(browser)
    assert "recorded rating" in message, message


if __name__ == "__main__":
    main()
