"""Big results print short (issue 21 item 5: ``print(site_calibration)`` dumped 25 kB;
review of stop 34: the site's lines printed 10 kB, its learned responses 5 kB, an
influence line 4.6 kB).  Each repr is one line under 200 characters that names what it
holds; the numbers in it are the object's own."""


def test_the_site_calibrations_parts_print_in_one_short_line(small_site_calibrated):
    _, _, records, site = small_site_calibrated
    lines = site.lines
    responses = site.responses[1]
    for obj, name in ((site, "SiteCalibration"), (lines, "MultiRunCalibration"),
                      (lines.line, "InfluenceLine"), (responses, "LearnedResponses")):
        text = repr(obj)
        assert text.startswith(name + "(") and "\n" not in text and len(text) < 200, text
    assert f"{len(lines.line.channels)} channels" in repr(lines)
    used = sum(1 for r in lines.runs if not r.rejected)
    assert f"{used} of {len(lines.runs)} runs" in repr(lines)
    assert f"{lines.truck_weight / 1e3:.1f} kN" in repr(lines)
    assert f"{responses.channels[0]}, {responses.channels[1]}" in repr(responses)
    assert f"{lines.line.x.size} ordinates" in repr(lines.line)
    assert len(lines.runs) <= len(records)
    run = repr(lines.runs[0])
    assert run.startswith("RunFit(") and len(run) < 200, run
