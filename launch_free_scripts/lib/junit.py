"""Writes the JUnit XML of the launch-free scripts' own test cases.

test.sh counts the cases of every XML file in its results folder
(lib/count_results.py): a case passes unless it holds a <failure>.

From Python (lib/ on sys.path, e.g. PYTHONPATH=launch_free_scripts/lib):
    import junit
    junit.write(OUT, SUITE, [junit.Case(NAME, failure=MESSAGE, ...), ...])
From a shell, one case:
    junit.py OUT SUITE CASE [--time S] [--system-out FILE] [--failure MESSAGE]
             [--failure-text FILE] [--tail N]
  An empty MESSAGE is a pass. FILEs are read with errors replaced; --tail N
  keeps their last N characters.
The class name of every case is the suite's name.
"""
import argparse
import xml.etree.ElementTree as ET


class Case:
    """One test case: it failed when `failure` (the one-line message) is set."""

    def __init__(self, name, failure=None, failure_text=None, system_out=None, time=None):
        self.name = name
        self.failure = failure
        self.failure_text = failure_text
        self.system_out = system_out
        self.time = time


def write(out, suite_name, cases):
    """Writes cases as the suite suite_name to the file out; returns the failure count."""
    failures = sum(1 for c in cases if c.failure is not None)
    suite = ET.Element("testsuite", name=suite_name, tests=str(len(cases)),
                       failures=str(failures))
    for c in cases:
        attributes = {"classname": suite_name, "name": c.name}
        if c.time is not None:
            attributes["time"] = str(c.time)
        case = ET.SubElement(suite, "testcase", **attributes)
        if c.system_out is not None:
            ET.SubElement(case, "system-out").text = c.system_out
        if c.failure is not None:
            ET.SubElement(case, "failure", message=c.failure).text = c.failure_text
    ET.ElementTree(suite).write(out, encoding="utf-8", xml_declaration=True)
    return failures


def read_tail(path, tail=None):
    """The text of the file path (its last `tail` characters when set)."""
    with open(path, errors="replace") as f:
        text = f.read()
    return text[-tail:] if tail else text


def main():
    parser = argparse.ArgumentParser(description="Writes one JUnit test case.")
    parser.add_argument("out")
    parser.add_argument("suite")
    parser.add_argument("case")
    parser.add_argument("--time")
    parser.add_argument("--system-out", metavar="FILE")
    parser.add_argument("--failure", metavar="MESSAGE")
    parser.add_argument("--failure-text", metavar="FILE")
    parser.add_argument("--tail", type=int)
    args = parser.parse_args()
    text = lambda path: read_tail(path, args.tail) if path else None
    write(args.out, args.suite, [Case(args.case, failure=args.failure or None,
                                      failure_text=text(args.failure_text),
                                      system_out=text(args.system_out), time=args.time)])


if __name__ == "__main__":
    main()
