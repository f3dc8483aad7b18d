<?xml version="1.0" encoding="utf-8"?>
<!DOCTYPE TS>
<TS version="2.1">
<context>
    <name>WorkCal</name>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="97"/>
        <source>no scan given: import a scan first (WorkCal &gt; Import scan)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="528"/>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="576"/>
        <source>WorkCal calibration</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="709"/>
        <source>Show workpiece model in the robot frame</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="712"/>
        <source>Deviation map</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="723"/>
        <source>Show placed workpiece model</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_view.py" line="178"/>
        <source>WorkCal deviation map</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_view.py" line="362"/>
        <source>Deviation (mm)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_view.py" line="362"/>
        <source>tolerance +-{} mm</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_view.py" line="364"/>
        <source>red: material added</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_view.py" line="364"/>
        <source>blue: material removed</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_view.py" line="365"/>
        <source>grey: no model near</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/calibrate.py" line="31"/>
        <source>calibration needs a {}: import or choose it first</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/calibrate.py" line="46"/>
        <location filename="../../workcal_wb/gui/commands/models.py" line="226"/>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="67"/>
        <source>another task panel is open; close it first</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="30"/>
        <location filename="../../workcal_wb/gui/commands/models.py" line="179"/>
        <source>All files</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="30"/>
        <source>Scans</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="45"/>
        <source>Scan units</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="46"/>
        <source>Length unit of the numbers in scan files
(asked once; change it in the WorkCal preferences, parameter ScanUnits):</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="50"/>
        <source>import cancelled: no unit chosen</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="66"/>
        <source>no scan file given</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="69"/>
        <source>unknown length unit {!r}; use one of {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="79"/>
        <source>Reading {}...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="88"/>
        <source>imported {} ({} points, read as {})</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="132"/>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="80"/>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="82"/>
        <source>Import scan</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/models.py" line="40"/>
        <location filename="../../workcal_wb/gui/commands/models.py" line="105"/>
        <location filename="../../workcal_wb/gui/commands/models.py" line="102"/>
        <location filename="../../workcal_wb/gui/commands/models.py" line="199"/>
        <source>Choose models</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/models.py" line="43"/>
        <location filename="../../workcal_wb/gui/commands/models.py" line="205"/>
        <source>setup: scan {}, workpiece model {}, reference model {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/models.py" line="110"/>
        <source>Scan (frame S)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/models.py" line="111"/>
        <source>Workpiece model X-A</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/models.py" line="112"/>
        <source>Reference model B-P</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/models.py" line="121"/>
        <source>From file...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/models.py" line="127"/>
        <source>The workpiece model is used in its own frame X (the toolpath's frame); the reference model must be placed where the reference object stands in the robot base frame B.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/models.py" line="141"/>
        <source>(none)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/models.py" line="157"/>
        <source>{} cannot be chosen as the {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/models.py" line="178"/>
        <location filename="../../workcal_wb/gui/commands/models.py" line="185"/>
        <source>Model file</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/models.py" line="179"/>
        <source>Models</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/preferences.py" line="33"/>
        <location filename="../../workcal_wb/gui/progress.py" line="52"/>
        <source>WorkCal</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="40"/>
        <source>{} scans in {}: select the one to use</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="41"/>
        <source>no scan in {}: import one first (WorkCal &gt; Import scan) or select a point cloud or mesh</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="72"/>
        <source>picking needs the 3D view of {}: activate it first</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="106"/>
        <location filename="../../workcal_wb/gui/picking.py" line="320"/>
        <source>Pick region</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="131"/>
        <source>workpiece model</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="132"/>
        <source>reference model</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="134"/>
        <source>automatic regions need the {}: choose it first (WorkCal &gt; Choose models)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="146"/>
        <source>Finding the workpiece and the reference in {}...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="147"/>
        <source>Automatic regions</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="150"/>
        <source>Find regions automatically</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="155"/>
        <source>regions of {} found: workpiece {} points, reference {} points; check them and correct with the pick tools if needed</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="174"/>
        <source>{} has no regions to clear</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="176"/>
        <source>Clear regions</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="179"/>
        <source>regions of {} cleared</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="94"/>
        <source>report written: {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="164"/>
        <source>study {}: {} (targets {}); plot {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="211"/>
        <source>Study</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="229"/>
        <source>study {} started (results in {})</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="297"/>
        <source>Studies</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="298"/>
        <source>Study to run on simulated scenes (quick settings, about a minute):</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/toolpath.py" line="50"/>
        <source>WorkCal calibrated toolpath</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/toolpath.py" line="59"/>
        <source>{}: {} moves carried into the robot base frame with {} ({})</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/toolpath.py" line="90"/>
        <source>wrote {}: {}, {} moves from {}, calibration {}{}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/toolpath.py" line="119"/>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="188"/>
        <source>Toolpath</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/toolpath.py" line="120"/>
        <source>Toolpath in the workpiece frame X:</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/toolpath.py" line="127"/>
        <source>Open G-code</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/toolpath.py" line="203"/>
        <source>Export robot program</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="74"/>
        <source>a selection needs at least 3 corners</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="382"/>
        <location filename="../../workcal_wb/gui/picking.py" line="370"/>
        <source>Pick scan regions</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="389"/>
        <source>Region</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="390"/>
        <source>Workpiece (X-A)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="391"/>
        <source>Reference object (B-P)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="392"/>
        <source>Tool</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="393"/>
        <source>Box</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="393"/>
        <source>Lasso</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="394"/>
        <source>Mode</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="395"/>
        <source>Replace</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="395"/>
        <source>Add (Shift)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="396"/>
        <source>Subtract (Ctrl)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="404"/>
        <source>Undo last pick</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="406"/>
        <source>Clear this region</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="411"/>
        <source>Box: drag with the left button.  Lasso: click the corners (or drag), then right-click, press Enter or click the first corner.  Shift adds, Ctrl subtracts, Esc drops the shape.  The middle button and the wheel still pan and zoom.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="455"/>
        <source>Scan: {} ({} points)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="457"/>
        <source>Workpiece: {} points    Reference: {} points</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="525"/>
        <source>WorkCal: regions of {}: workpiece {} points, reference {} points
</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/progress.py" line="50"/>
        <source>Cancel</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/progress.py" line="58"/>
        <location filename="../../workcal_wb/gui/task_panels/common.py" line="62"/>
        <source>{} cancelled</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="63"/>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="70"/>
        <source>calibration cancelled</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="171"/>
        <source>Calibrate workpiece</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="174"/>
        <source>Inputs</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="180"/>
        <source>The scene scan: workpiece and reference seen from one position</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="181"/>
        <source>The workpiece model X-A, in its own frame X</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="182"/>
        <source>The reference model B-P, in the robot base frame B</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="183"/>
        <source>Optional: the uncertainty is reported at this toolpath's cutting points</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="185"/>
        <source>Scan</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="186"/>
        <source>Workpiece model</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="187"/>
        <source>Reference model</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="191"/>
        <source>Options</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="195"/>
        <source>robust: trimmed point-to-plane ICP (default); icp and hausdorff: the paper's least-squares and Hausdorff measures</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="202"/>
        <source>Residuals and the uncertainty must stay within it</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="203"/>
        <source>Automatic</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="204"/>
        <source>Use picked regions</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="212"/>
        <source>Bootstrap refits for the uncertainty bound</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="213"/>
        <source>Show the workpiece model in the robot frame</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="214"/>
        <source>Method</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="215"/>
        <source>Tolerance</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="216"/>
        <source>Regions</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="217"/>
        <source>Seed</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="218"/>
        <source>Resamples</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="225"/>
        <source>Press OK to calibrate.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="345"/>
        <source>Calibrating</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="346"/>
        <source>starting</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="347"/>
        <source>calibrating {} against {} and {} ...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="356"/>
        <source>Cancelling...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="400"/>
        <source>Calibration {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="408"/>
        <source>calibration not done: {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="409"/>
        <source>Error: {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/calibrate_panel.py" line="416"/>
        <source>calibration cancelled; the document is unchanged</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/common.py" line="79"/>
        <source>no document open</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/common.py" line="103"/>
        <source>no calibration in the document: run WorkCal &gt; Calibrate first</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/common.py" line="113"/>
        <source>Calibration not ok</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/common.py" line="114"/>
        <source>The calibration did not pass its quality gates.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/common.py" line="115"/>
        <source>Use it anyway? The result is marked FORCED; check the workpiece position by hand before running the program.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/common.py" line="136"/>
        <source>using a calibration that did not pass its gates (FORCED)</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_AutoRegions</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="187"/>
        <source>Find regions automatically</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="188"/>
        <source>Find the workpiece and the reference object in the scan with their models (removes the platform, splits the objects and matches them); correct the result with the pick tools</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_Calibrate</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/calibrate.py" line="56"/>
        <source>Calibrate</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/calibrate.py" line="57"/>
        <source>Match the workpiece and the reference block in the scan and compute W = V^-1 U, the workpiece frame in the robot base frame</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_ChooseModels</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/models.py" line="236"/>
        <source>Choose models...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/models.py" line="237"/>
        <source>Choose the scan, the workpiece model X-A and the reference model B-P (Part shapes, meshes or point clouds from the document or from files)</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_ClearRegions</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="206"/>
        <source>Clear regions</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="207"/>
        <source>Remove the workpiece and reference regions of the scan</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_DeviationMap</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="37"/>
        <source>Deviation map</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="38"/>
        <source>Colour the workpiece points of the scan by their signed distance to the placed model: red where clay was added, blue where it was removed</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_ExportToolpath</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/toolpath.py" line="176"/>
        <source>Export robot program</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/toolpath.py" line="177"/>
        <source>Write the toolpath through the calibration as KUKA KRL, ABB RAPID, URScript, Fanuc LS, G-code or CSV</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_ImportScan</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="113"/>
        <source>Import scan...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="114"/>
        <source>Read a 3D scan of the mounted workpiece and the reference object (PLY, PCD, XYZ, ASC, PTS, CSV, E57, STL, OBJ, OFF); it becomes the document's scan</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_PickBox</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="95"/>
        <source>Pick region (box)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="96"/>
        <source>Pick the workpiece or the reference region of the scan by dragging boxes in the 3D view (Shift adds, Ctrl subtracts)</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_PickLasso</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="111"/>
        <source>Pick region (lasso)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="112"/>
        <source>Pick the workpiece or the reference region of the scan by drawing polygons in the 3D view; right-click or Enter closes</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_Preferences</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/preferences.py" line="91"/>
        <source>Preferences...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/preferences.py" line="92"/>
        <source>Default units, tolerance, matching method and export format</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_Report</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="119"/>
        <source>Calibration report</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="120"/>
        <source>Write the HTML report of the calibration (poses, residuals, uncertainty, quality gates) and open it</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_Studies</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="281"/>
        <source>Studies...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="282"/>
        <source>Run one of the accuracy studies on a simulated scene and show its plot</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_TransformToolpath</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/toolpath.py" line="147"/>
        <source>Calibrated toolpath</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/toolpath.py" line="148"/>
        <source>Carry a Path/CAM Job, an operation or a G-code file from the workpiece frame into the robot base frame with the calibration, shown as a Path object</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>Workbench</name>
    <message>
        <location filename="../../workcal_wb/gui/workbench.py" line="18"/>
        <source>WorkCal</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/workbench.py" line="19"/>
        <source>Locate a freeform workpiece for a robot from one 3D scan and calibrate its toolpath</source>
        <translation type="unfinished"></translation>
    </message>
</context>
</TS>
