"""Run by load-test.sh: the page of `mach-vision panel --profile` (its first output line names
the address) shows the panel folder's state — its sequence number, and M281's refusal as the
last call and as Why NG?. Arguments: the panel's output file, the folder's state.json."""
import json
import sys
import time
import urllib.request

out_path, state_path = sys.argv[1], sys.argv[2]
with open(state_path) as f:
    folder = json.load(f)
deadline = time.monotonic() + 30
page = None
while time.monotonic() < deadline:
    with open(out_path) as f:
        line = f.readline()
    if "http://" in line:
        url = "http://" + line.split("http://")[1].split()[0].rstrip("/") + "/state.json"
        page = json.load(urllib.request.urlopen(url, timeout=10))
        if page.get("source", "").endswith("(state %d)" % folder["seq"]):
            break
    time.sleep(0.1)
else:
    sys.exit("load-test: the panel never showed the folder's state %d: %s / %r" % (folder["seq"], page, line))
call = page.get("call") or {}
if call.get("mcode") != 281 or call.get("ok") is not False or "K matrix is zero" not in (page.get("why_ng") or ""):
    sys.exit("load-test: the panel's page does not show M281's refusal: %s" % page)
print("load-test: mach-vision panel --profile shows the folder's state %d (M281 refused)" % folder["seq"])
