"""Counts test cases in the JUnit XML files of a catkin test_results folder.

Prints failing cases, then the final line "N passed, N failed"; exits 1 on any
failure. A test binary that produced no result (crash, timeout) counts as a
failure: catkin writes a MISSING-RESULT file with a failure for it.
"""
import glob
import os
import sys
import xml.etree.ElementTree as ET


def main():
    folder, extra = sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 0
    passed, failed = 0, extra
    files = sorted(glob.glob(os.path.join(folder, "*.xml")))
    for path in files:
        try:
            root = ET.parse(path).getroot()
        except ET.ParseError as err:
            print(f"unreadable result {os.path.basename(path)}: {err}")
            failed += 1
            continue
        for case in root.iter("testcase"):
            name = f"{case.get('classname')}.{case.get('name')}"
            if case.find("skipped") is not None or case.get("status") == "notrun":
                continue
            if case.find("failure") is not None or case.find("error") is not None:
                failed += 1
                print(f"FAILED {os.path.basename(path)}: {name}")
            else:
                passed += 1
    if not files:
        print("no test results found")
        failed += 1
    print(f"{passed} passed, {failed} failed")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
