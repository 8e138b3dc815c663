#!/usr/bin/python3
"""Counts test cases in JUnit XML files (gtest and rostest results): prints "passed failed skipped".

catkin_test_results counts a gtest file's <testsuites> and <testsuite> both, doubling the total, so the
test script counts <testcase> elements itself. A file with no test case counts as one failure: a test
binary that crashed before writing results must not look like success. A failure's message is printed
under its name (at most 12 lines each).
"""
import sys
import xml.etree.ElementTree as ET

passed = failed = skipped = 0
for path in sys.argv[1:]:
    try:
        cases = list(ET.parse(path).getroot().iter("testcase"))
    except ET.ParseError as e:
        print(f"{path}: unreadable results: {e}", file=sys.stderr)
        failed += 1
        continue
    if not cases:
        print(f"{path}: no test cases", file=sys.stderr)
        failed += 1
    for c in cases:
        if c.find("failure") is not None or c.find("error") is not None:
            failed += 1
            print(f"FAILED: {c.get('classname')}.{c.get('name')} ({path})", file=sys.stderr)
            # The assertion's own words, so that a log holding only this summary (CI's) says why.
            for f in list(c.iter("failure")) + list(c.iter("error")):
                text = (f.text or f.get("message") or "").strip().splitlines()
                for line in text[:12]:
                    print(f"    {line}", file=sys.stderr)
        elif c.find("skipped") is not None or c.get("result") == "skipped" or c.get("status") == "notrun":
            skipped += 1
            msg = c.find("skipped")
            why = msg.get("message", "") if msg is not None else ""
            print(f"SKIPPED: {c.get('classname')}.{c.get('name')} {why}".strip(), file=sys.stderr)
        else:
            passed += 1
print(passed, failed, skipped)
