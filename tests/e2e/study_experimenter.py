#!/usr/bin/env python3
"""The experimenter at a people study's console, in headless Chromium
(Selenium): adds participant A, then for each of their trials checks that
the page names the device it needs and that it is there, presses Start,
waits for the trial to end (and presses Start again when it is offered
again: its vehicle was lost), fills in the questionnaire after its condition,
and at the end finishes the open study. Prints one line per trial started
("started CONDITION DEVICE") so the test driving the trials' windows can
follow; exits 0 when every trial ran, 1 with the reason otherwise.

usage: study_experimenter.py URL PARTICIPANT TRIALS QUESTIONNAIRE
       (run by tests/e2e/test_people_study.cpp)
"""
import json
import sys
import time
import urllib.request

from selenium import webdriver
from selenium.webdriver.chrome.options import Options
from selenium.webdriver.chrome.service import Service
from selenium.common.exceptions import StaleElementReferenceException, WebDriverException
from selenium.webdriver.common.by import By
from selenium.webdriver.support import expected_conditions
from selenium.webdriver.support.ui import WebDriverWait

TIMEOUT_S = 120  # a trial on a loaded 2-core machine


def status(url):
    """The console's status.json: a small request, not a page for the browser
    to render. {} when it did not answer (in time: a loaded machine; or not
    yet: the study still starting): asked again."""
    try:
        with urllib.request.urlopen(url + "status.json", timeout=10) as reply:
            return json.load(reply)
    except OSError:  # URLError (refused), a timeout, a connection cut
        return {}


def wait_status(url, ready, what):
    """The console's status once `ready(status)`."""
    deadline = time.monotonic() + TIMEOUT_S
    while time.monotonic() < deadline:
        now = status(url)
        if ready(now):
            return now
        time.sleep(0.25)
    raise AssertionError(f"waited {TIMEOUT_S} s for {what}; the console's status: {now}")


def until(browser, url, find, what, ready=None):
    """Waits until `ready(status)` (the console's status.json, read cheaply
    while a trial runs), then loads the schedule until `find` returns
    something truthy."""
    deadline = time.monotonic() + TIMEOUT_S
    while time.monotonic() < deadline:
        if ready is None or ready(status(url)):
            browser.get(url)
            found = find()
            if found:
                return found
        time.sleep(0.25)
    raise AssertionError(f"waited {TIMEOUT_S} s for {what}; the page said:\n{browser.page_source[:3000]}")


def replaced(element):
    """True once the page that held `element` is replaced. Chromium says so
    as a stale element or, now and then, as a node that "does not belong to
    the document" (a plain WebDriverException, which staleness_of lets through)."""
    try:
        element.is_enabled()
        return False
    except StaleElementReferenceException:
        return True
    except WebDriverException as e:
        if "does not belong to the document" in str(e):
            return True
        raise


def elements(browser, selector):
    return browser.find_elements(By.CSS_SELECTOR, selector)


def run(browser, url, participant, trials, questionnaire):
    # Started beside the study: its console answers first (Chromium refuses
    # to load a page whose port is not yet open).
    wait_status(url, lambda s: s != {}, "the console to answer")
    until(browser, url, lambda: elements(browser, "#new-participant"), "the participants' form")
    browser.find_element(By.ID, "new-participant").send_keys(participant)
    browser.find_element(By.ID, "add").click()
    for number in range(1, trials + 1):
        while True:
            # The trial offered: its device named, and there (no line saying what is missing).
            until(browser, url, lambda: elements(browser, "#start"), f"trial {number}'s Start",
                  lambda s: s.get("next", "") != "")
            device = browser.find_element(By.ID, "next-device").text
            missing = elements(browser, "#device-missing")
            assert not missing, missing[0].text
            condition = browser.find_element(By.ID, "next").text.split(", ")[1].split(" ")[0]
            browser.find_element(By.ID, "start").click()
            print("started", condition, device.split()[1], flush=True)
            # Taken by the study; then done (its questionnaire awaited), or
            # offered again (its vehicle was lost): started again.
            wait_status(url, lambda s: s and (s["next"] == "" or s["trials_done"] >= number),
                        f"trial {number} to start")
            if wait_status(url, lambda s: s and (s["trials_done"] >= number or s["next"] != ""),
                           f"the end of {condition}")["trials_done"] >= number:
                break
            print("offered again", condition, flush=True)
        # Over: the schedule links the condition's questionnaire.
        link = f"a[href*='condition={condition}&'][href*='name={questionnaire}']"
        form = until(browser, url, lambda: elements(browser, link),
                     f"the questionnaire after {condition}")
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
    until(browser, url, lambda: elements(browser, "#finish"), "the Finish button",
          lambda s: s.get("waiting_for_participants", False))
    finish = browser.find_element(By.ID, "finish")
    finish.click()
    # The console's answer replaces the page: only then has the study the
    # press (quitting Chromium at once could cut the POST, and the study
    # waited for more participants for ever).
    WebDriverWait(browser, TIMEOUT_S).until(lambda _: replaced(finish))
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
