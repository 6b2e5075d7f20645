#!/usr/bin/env python3
"""The experimenter at a people study's console, in headless Chromium
(Selenium): adds participant A, then for each of their trials checks that
the page names the device it needs and that it is there, presses Start,
waits for the trial to end, fills in the questionnaire after its condition,
and at the end finishes the open study. Prints one line per trial started
("started CONDITION DEVICE") so the test driving the trials' windows can
follow; exits 0 when every trial ran, 1 with the reason otherwise.

usage: study_experimenter.py URL PARTICIPANT TRIALS QUESTIONNAIRE
       (run by tests/e2e/test_people_study.cpp)
"""
import sys
import time

from selenium import webdriver
from selenium.webdriver.chrome.options import Options
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By
from selenium.webdriver.support import expected_conditions
from selenium.webdriver.support.ui import WebDriverWait

TIMEOUT_S = 120  # a trial on a loaded 2-core machine


def until(browser, url, find, what):
    """Reloads the schedule (it refreshes itself only while something
    changes) until `find` returns something truthy."""
    deadline = time.monotonic() + TIMEOUT_S
    while time.monotonic() < deadline:
        browser.get(url)
        found = find()
        if found:
            return found
        time.sleep(0.5)
    raise AssertionError(f"waited {TIMEOUT_S} s for {what}; the page said:\n{browser.page_source[:3000]}")


def elements(browser, selector):
    return browser.find_elements(By.CSS_SELECTOR, selector)


def run(browser, url, participant, trials, questionnaire):
    until(browser, url, lambda: elements(browser, "#new-participant"), "the participants' form")
    browser.find_element(By.ID, "new-participant").send_keys(participant)
    browser.find_element(By.ID, "add").click()
    for number in range(1, trials + 1):
        # The trial offered: its device named, and there (no line saying what is missing).
        until(browser, url, lambda: elements(browser, "#start"), f"trial {number}'s Start")
        device = browser.find_element(By.ID, "next-device").text
        missing = elements(browser, "#device-missing")
        assert not missing, missing[0].text
        condition = browser.find_element(By.ID, "next").text.split(", ")[1].split(" ")[0]
        browser.find_element(By.ID, "start").click()
        print("started", condition, device.split()[1], flush=True)
        # Over when the schedule links the condition's questionnaire.
        link = f"a[href*='condition={condition}&'][href*='name={questionnaire}']"
        form = until(browser, url, lambda: elements(browser, link), f"the end of {condition}")
        browser.get(form[0].get_attribute("href"))
        WebDriverWait(browser, 30).until(
            expected_conditions.presence_of_element_located((By.ID, "questionnaire")))
        for item in ("easy_to_learn", "efficient"):
            browser.find_element(By.CSS_SELECTOR, f'input[name="{item}"][value="4"]').click()
        browser.find_element(By.ID, "submit").click()
        result = WebDriverWait(browser, 30).until(
            expected_conditions.presence_of_element_located((By.ID, "result"))).text
        assert f"recorded {questionnaire}" in result, result
        print("answered", condition, flush=True)
    # Every trial of the open study done: it waits for more people, or Finish.
    until(browser, url, lambda: elements(browser, "#finish"), "the Finish button")
    browser.find_element(By.ID, "finish").click()
    print("finished", flush=True)


def main():
    url, participant, trials, questionnaire = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
    options = Options()
    for argument in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu"):
        options.add_argument(argument)
    browser = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
    browser.set_page_load_timeout(30)
    try:
        run(browser, url, participant, trials, questionnaire)
    except AssertionError as e:
        print("experimenter:", e, file=sys.stderr, flush=True)
        return 1
    finally:
        browser.quit()
    return 0


if __name__ == "__main__":
    sys.exit(main())
