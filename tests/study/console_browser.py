#!/usr/bin/env python3
"""The experimenter's console in a real browser (headless Chromium through
Selenium): a participant fills in their background (the demographics, once
before their first trial) and both questionnaires after the condition they
drove, the rating tree walked one question at a time; the same form sent
twice and an incomplete one are refused on the page; the experimenter
writes a note on a trial from the schedule; the database holds exactly one
row per answer and the note as written.

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
            ("A", "", "demographics", "age_band", "25-34"),
            ("A", "", "demographics", "gender", "self-described"),
            ("A", "", "demographics", "gender_description", "in my own words"),
            ("A", "", "demographics", "handedness", "left"),
            ("A", "", "demographics", "video_games", "weekly"),
            ("A", "", "demographics", "driving", "no-licence"),
            ("A", "", "demographics", "haptic_devices", "never"),
        ])
        assert rows == expected, f"rows in the database:\n{rows}\nexpected:\n{expected}"
        notes = sqlite3.connect(db).execute("SELECT participant, position, text FROM study_notes").fetchall()
        assert notes == [("A", 1, NOTE)], f"notes in the database: {notes}"
        print("console_browser: ok,", len(rows), "answer rows,", len(notes), "note")
    finally:
        server.stdin.close()
        server.wait(timeout=30)


# A note in two scripts and markup, kept as written and shown as text.
NOTE = "looked at the hands <b>not</b> the screen, 手を見ていた"


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
    # The background first: the schedule links it from A's first trial.
    browser.get(url)
    browser.find_element(By.CSS_SELECTOR, "a.demographics").click()
    WebDriverWait(browser, 30).until(expected_conditions.presence_of_element_located((By.ID, "questionnaire")))
    for item, value in (("age_band", "25-34"), ("gender", "self-described"), ("handedness", "left"),
                        ("video_games", "weekly"), ("driving", "no-licence"), ("haptic_devices", "never")):
        browser.find_element(By.CSS_SELECTOR, f'input[name="{item}"][value="{value}"]').click()
    browser.find_element(By.NAME, "gender_description").send_keys("in my own words")
    browser.find_element(By.ID, "submit").click()
    message = result(browser)
    assert "recorded demographics" in message, message
    browser.get(url)  # answered: the schedule says so and links it no more
    assert not browser.find_elements(By.CSS_SELECTOR, "a.demographics")

    # A note on A's first trial, from its row of the schedule.
    row = browser.find_elements(By.CSS_SELECTOR, "#schedule tr")[1]
    row.find_element(By.NAME, "text").send_keys(NOTE)
    row.find_element(By.CSS_SELECTOR, "form.note button").click()
    WebDriverWait(browser, 30).until(
        expected_conditions.text_to_be_present_in_element((By.ID, "schedule"), NOTE))

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

    walk_rating_tree(browser, rating)
    browser.find_element(By.ID, "submit").click()
    message = result(browser)
    assert "recorded rating" in message, message


def walk_rating_tree(browser, rating):
    """The 1-10 rating tree, one question at a time as the thesis's decision
    tree: only the question the last answer leads to shows, then only the
    ratings of the band the path ends in; changing an answer drops what came
    after it. Ends on the path to 5 (satisfactory? no)."""
    browser.get(rating)

    def shown():
        """The ids of the tree's steps on screen (questions and bands), top to bottom."""
        return [e.get_attribute("id") for e in browser.find_elements(
            By.CSS_SELECTOR, "div.tree .tree-node, div.tree .tree-band") if e.is_displayed()]

    def answer(node, value):
        browser.find_element(By.CSS_SELECTOR, f'input[name="rating.node.{node}"][value="{value}"]').click()

    def ratings():
        return sorted(int(e.get_attribute("value")) for e in browser.find_elements(
            By.CSS_SELECTOR, 'input[name="rating"]') if e.is_displayed())

    assert shown() == ["rating-step-controllable"], shown()
    assert ratings() == [], ratings()
    answer("controllable", "no")  # straight to 10
    assert shown() == ["rating-step-controllable", "rating-step-uncontrollable"], shown()
    assert ratings() == [10], ratings()
    answer("controllable", "yes")  # changed: the band goes, the next question comes
    assert shown() == ["rating-step-controllable", "rating-step-adequate"], shown()
    answer("adequate", "yes")
    assert shown()[-1] == "rating-step-satisfactory", shown()
    answer("satisfactory", "yes")
    assert ratings() == [1, 2, 3], ratings()
    browser.find_element(By.CSS_SELECTOR, 'input[name="rating"][value="2"]').click()
    answer("adequate", "no")  # back up: satisfactory's question and the 2 are gone
    assert shown() == ["rating-step-controllable", "rating-step-adequate", "rating-step-inadequate"], shown()
    assert ratings() == [7, 8, 9], ratings()
    assert not browser.find_elements(By.CSS_SELECTOR, 'input[name="rating"]:checked')
    assert not browser.find_elements(By.CSS_SELECTOR, 'input[name="rating.node.satisfactory"]:checked')
    answer("adequate", "yes")
    answer("satisfactory", "no")
    assert ratings() == [4, 5, 6], ratings()
    browser.find_element(By.CSS_SELECTOR, 'input[name="rating"][value="5"]').click()


if __name__ == "__main__":
    main()
