<?xml version="1.0" encoding="utf-8"?>
<!DOCTYPE TS>
<TS version="2.1">
<context>
    <name>App::Property</name>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="47"/>
        <location filename="../../workcal_wb/fc/setup.py" line="30"/>
        <source>The scene scan: the workpiece and the reference object seen at once (scanner frame S)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="49"/>
        <source>The workpiece model in its own frame, the toolpath's (X-A in frame X); a Part, Mesh or Points object</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="52"/>
        <source>The fixed reference object's model, where it stands in the robot base frame (B-P in B)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="54"/>
        <source>Optional Path/CAM Job or operation: the uncertainty is reported at its cutting points</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="56"/>
        <source>Optional G-code file (used when Toolpath is empty): the uncertainty is reported at its cutting points</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="61"/>
        <source>How the models are fitted to the scan: robust (default), icp or hausdorff (the paper's two measures)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="64"/>
        <source>Milling tolerance: residuals and the uncertainty at the toolpath must stay within it</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="66"/>
        <source>Auto: find the workpiece and the reference in the scan; Picked: use the regions picked on the scan</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="69"/>
        <source>Random seed of the search and the uncertainty estimate: the same seed gives the same W</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="71"/>
        <source>Refits of both matches the uncertainty is estimated from (bootstrap)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="73"/>
        <source>Use Scanner as where the scanner stood (else the scan file's position, or none: the views are judged without it)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="76"/>
        <source>Where the scanner stood, the origin of the scanner frame S, in the scan's coordinates (used when ScannerOn is true)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="79"/>
        <source>The platform's up direction in the scan's coordinates, the side the objects stand on (0, 0, 0: from the data)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="82"/>
        <source>Show the axes of the robot base frame (B), the scanner frame (S) and the workpiece frame (X)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="85"/>
        <source>Length of the frame axes</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="91"/>
        <source>ok: W can be used; ambiguous: another pose fits almost as well; failed: W must not be used (see Reasons); error: the inputs could not be calibrated</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="94"/>
        <source>Where the workpiece is in the robot base frame: W = ^B X = V^-1 U, the workpiece frame X in the robot base frame B</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="97"/>
        <source>W's rotation as the paper's Z-Y-Z Euler angles phi, theta, psi (degrees)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="99"/>
        <source>W's rotation angle about its principal axis: Omega = acos((trace(R) - 1) / 2)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="101"/>
        <source>Where the workpiece is in the scan: U = ^S X, the workpiece frame X in the scanner frame S</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="103"/>
        <source>Where the robot base is in the scan: V = ^S B, the robot base frame B in the scanner frame S (from the reference object)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="106"/>
        <source>RMS distance of the workpiece's scan points to its model</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="108"/>
        <source>RMS distance of the reference object's scan points to its model</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="110"/>
        <source>How far a toolpath point may be off because of the calibration (0 without a toolpath)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="112"/>
        <source>How far a point of the workpiece surface may be off because of the calibration</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="114"/>
        <source>How far W's rotation may be off</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="116"/>
        <source>Why the calibration is not ok (failed checks, another pose that fits)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="118"/>
        <source>Warnings of the calibration</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="119"/>
        <source>Seconds the calibration took</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="121"/>
        <source>Someone checked this result and accepted W (cleared when it is calibrated again)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="125"/>
        <source>The complete CalibrationResult as JSON (for exporters and reports)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="127"/>
        <source>Fingerprint of the inputs the result was computed from</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_map.py" line="29"/>
        <source>The calibration whose workpiece match is shown</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_map.py" line="31"/>
        <source>The colours reach full strength at 3 tolerances (set Limit to choose another limit)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_map.py" line="33"/>
        <source>Deviation at which the colours reach full red (added) and blue (removed)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_map.py" line="35"/>
        <source>Points within this distance of the model are green (the calibration's tolerance)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_map.py" line="37"/>
        <source>Mean signed deviation</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_map.py" line="38"/>
        <source>RMS deviation</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_map.py" line="39"/>
        <source>Largest deviation into the model (material removed)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_map.py" line="41"/>
        <source>Largest deviation out of the model (material added)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_map.py" line="43"/>
        <source>% of points within the tolerance</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_map.py" line="45"/>
        <source>Points with no model surface near them (grey)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_map.py" line="47"/>
        <source>Show the colour scale in the 3D view</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_map.py" line="49"/>
        <source>Signed deviation per point, mm (NaN: no surface near)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_map.py" line="51"/>
        <source>Colour per point</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/placed_model.py" line="42"/>
        <source>The model that is shown placed</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/placed_model.py" line="43"/>
        <source>The calibration that places it</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/placed_model.py" line="45"/>
        <source>Scan: over the scan points (workpiece by U, reference by V); RobotBase: in the robot base frame (workpiece by W)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/placed_model.py" line="48"/>
        <source>Which model it is</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/placed_model.py" line="49"/>
        <source>0: the calibration's pose; 1, 2...: the other poses the match found (for an ambiguous result)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/scan.py" line="67"/>
        <source>Length unit the file was read in; the points are stored in mm</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/scan.py" line="69"/>
        <source>File the scan was read from</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/scan.py" line="74"/>
        <source>Number of points</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/setup.py" line="33"/>
        <source>Model of the workpiece in its own frame, the toolpath's (X-A in frame X)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/setup.py" line="36"/>
        <source>Model of the fixed reference object, placed where it stands in the robot base frame (B-P in frame B)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/setup.py" line="40"/>
        <source>The toolpath to carry into the robot frame: a Path/CAM Job or operation</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/setup.py" line="43"/>
        <source>The toolpath as a G-code file (used when Toolpath is empty)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/toolpath.py" line="160"/>
        <source>The calibration whose W carries the toolpath into the robot base frame</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/toolpath.py" line="162"/>
        <source>The toolpath in the workpiece frame: a Path/CAM Job or operation</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/toolpath.py" line="164"/>
        <source>The toolpath as a G-code file (when Source is empty)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/toolpath.py" line="166"/>
        <source>Made from a calibration that did not pass its checks, because the user said so</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal</name>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="386"/>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="420"/>
        <location filename="../../workcal_wb/gui/task_panels/guide.py" line="134"/>
        <source>WorkCal calibration</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="389"/>
        <source>Calibration</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/calibration_object.py" line="438"/>
        <source>Accept the calibration</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_map.py" line="136"/>
        <source>WorkCal deviation map</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/deviation_map.py" line="139"/>
        <source>Deviation map of the workpiece</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/models.py" line="151"/>
        <source>Import model</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/placed_model.py" line="38"/>
        <source>Workpiece model on the scan</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/placed_model.py" line="39"/>
        <source>Reference model on the scan</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/placed_model.py" line="40"/>
        <source>Workpiece model in the robot frame</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/placed_model.py" line="171"/>
        <source>Show the models on the scan</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/placed_model.py" line="180"/>
        <location filename="../../workcal_wb/gui/view_providers/calibration.py" line="99"/>
        <source>Show the workpiece model in the robot frame</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/placed_model.py" line="215"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="235"/>
        <source>workpiece</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/placed_model.py" line="215"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="235"/>
        <source>reference object</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/placed_model.py" line="216"/>
        <source>The {} model is symmetric ({}): no scan can tell these poses apart; only a feature that breaks the symmetry (a mark, a fixture) would.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/placed_model.py" line="229"/>
        <source>turned as the other pose turns it, it covers itself</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/placed_model.py" line="233"/>
        <source>The two poses of the {} differ most around ({:.0f}, {:.0f}, {:.0f}) mm on its model, by up to {:.1f} mm: a scan that sees that part clearly, or a region picked to include it, would tell them apart.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/regions.py" line="73"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="85"/>
        <source>Find regions automatically</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/regions.py" line="85"/>
        <location filename="../../workcal_wb/gui/picking.py" line="461"/>
        <location filename="../../workcal_wb/gui/picking.py" line="449"/>
        <source>Pick scan regions</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/regions.py" line="94"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="91"/>
        <source>Clear regions</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/scan.py" line="379"/>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="98"/>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="83"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/scan.py" line="65"/>
        <source>Import scan</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/setup.py" line="63"/>
        <source>WorkCal setup</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/setup.py" line="116"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/models.py" line="33"/>
        <source>Choose models</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/setup.py" line="150"/>
        <source>Choose toolpath</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/toolpath.py" line="213"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="114"/>
        <source>Calibrated toolpath</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/fc/toolpath.py" line="221"/>
        <source>Toolpath in the robot frame ({})</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="31"/>
        <location filename="../../workcal_wb/gui/commands/models.py" line="64"/>
        <source>All files</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="31"/>
        <source>Scans</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="46"/>
        <source>Scan units</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="47"/>
        <source>Length unit of the numbers in scan files
(asked once; change it in the WorkCal preferences):</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="51"/>
        <source>import cancelled: no unit chosen</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="68"/>
        <source>no scan file given</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="71"/>
        <source>unknown length unit {!r}; use one of {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="82"/>
        <source>Reading {}...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/models.py" line="63"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/models.py" line="87"/>
        <source>Model file</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/models.py" line="64"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/models.py" line="15"/>
        <source>Models</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/preferences.py" line="35"/>
        <location filename="../../workcal_wb/gui/progress.py" line="52"/>
        <source>WorkCal</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/preferences.py" line="36"/>
        <source>automatic (3 tolerances)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/preferences.py" line="38"/>
        <source>Report folder</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/preferences.py" line="41"/>
        <source>Prepared models folder</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/preferences.py" line="43"/>
        <source>ask at the first import</source>
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
        <location filename="../../workcal_wb/gui/commands/regions.py" line="64"/>
        <source>picking needs the 3D view of {}: activate it first</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="119"/>
        <source>Finding the workpiece and the reference in {}...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="120"/>
        <source>Automatic regions</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="127"/>
        <source>study {}: {} (targets {}); plot {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="174"/>
        <source>Study</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="192"/>
        <source>study {} started (results in {})</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="254"/>
        <source>Studies</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="255"/>
        <source>Study to run on simulated scenes (quick settings, about a minute):</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/toolpath.py" line="54"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="15"/>
        <source>Toolpath</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="136"/>
        <source>a selection needs at least 3 corners</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="388"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="103"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="101"/>
        <source>Pick region</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="468"/>
        <source>Region</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="469"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="112"/>
        <source>Workpiece</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="469"/>
        <source>The points on the workpiece (matched to its model X-A)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="471"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="113"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="140"/>
        <source>Reference object</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="471"/>
        <source>The points on the fixed reference object (matched to its model B-P)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="473"/>
        <source>Tool</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="474"/>
        <source>Box</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="474"/>
        <source>Drag a rectangle</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="475"/>
        <source>Lasso</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="475"/>
        <source>Click the corners of a polygon</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="477"/>
        <source>Mode</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="478"/>
        <source>Replace</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="478"/>
        <source>The region becomes what you pick</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="479"/>
        <source>Add (Shift)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="479"/>
        <source>Add what you pick to the region</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="480"/>
        <source>Subtract (Ctrl)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="480"/>
        <source>Take what you pick out of the region</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="484"/>
        <source>Visible points only</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="486"/>
        <source>Take only the points you see, not those hidden behind them (e.g. the platform under the part)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="497"/>
        <source>Undo pick</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="498"/>
        <source>Undo the last pick</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="500"/>
        <source>Clear region</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="501"/>
        <source>Empty the region chosen above</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="506"/>
        <source>Box: drag with the left button.  Lasso: click the corners (or drag), then right-click, press Enter or click the first corner.  Shift adds, Ctrl subtracts, Esc drops the shape.  The middle button and the wheel still pan and zoom.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="551"/>
        <source>Scan: {} ({} points)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="553"/>
        <source>Workpiece: {} points
Reference: {} points</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/picking.py" line="634"/>
        <source>WorkCal: regions of {}: workpiece {} points, reference {} points
</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/progress.py" line="50"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="145"/>
        <source>Cancel</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/progress.py" line="58"/>
        <location filename="../../workcal_wb/gui/task_panels/common.py" line="64"/>
        <source>{} cancelled</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/common.py" line="101"/>
        <source>another task panel is open; close it first</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/common.py" line="150"/>
        <source>no document open</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/common.py" line="174"/>
        <source>no calibration in the document: run WorkCal &gt; Calibrate first</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/common.py" line="184"/>
        <source>Calibration not ok</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/common.py" line="185"/>
        <source>The calibration did not pass its quality gates.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/common.py" line="186"/>
        <source>Use it anyway? The result is marked FORCED; check the workpiece position by hand before running the program.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/common.py" line="206"/>
        <source>using a calibration that did not pass its gates (FORCED)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/guide.py" line="259"/>
        <source>Next: {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/runner.py" line="56"/>
        <location filename="../../workcal_wb/gui/task_panels/runner.py" line="63"/>
        <source>calibration cancelled</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="42"/>
        <source>auto</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="55"/>
        <source>{}: give X, Y and Z, or leave all three empty (automatic)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="60"/>
        <source>{}: {} is not a number</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="70"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="144"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="201"/>
        <source>Calibrate</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="71"/>
        <source>Calibrate: find where the workpiece is for the robot</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="72"/>
        <source>Match the workpiece (U = ^S X) and the reference object (V = ^S B) in the scan and compute W = V^-1 U, the workpiece in the robot base frame</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="87"/>
        <source>The milling tolerance: the fit of both models and the uncertainty at the toolpath must stay within it</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="89"/>
        <source>Tolerance</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="91"/>
        <source>Find the regions itself</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="92"/>
        <source>Find the workpiece and the reference object in the scan with their models</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="94"/>
        <source>Use the scan's regions</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="95"/>
        <source>Use the regions found or picked in the Regions step</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="100"/>
        <source>Advanced options</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="112"/>
        <source>How the models are fitted: robust (default) weighs down points off the model; icp and hausdorff are the paper's measures D and H</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="116"/>
        <source>Seed of the random search and of the uncertainty estimate: the same seed gives the same W</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="120"/>
        <source>How many times both matches are refitted on resampled points to estimate the uncertainty (bootstrap)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="122"/>
        <source>Scanner position</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="122"/>
        <source>Where the scanner stood when it took the scan, in the scan's coordinates (mm): the origin of the scanner frame S. It tells which side of each object the scan shows. Empty: the position the scan's file gives (PCD VIEWPOINT, E57 pose, PLY comment), else none</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="126"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="135"/>
        <source>Up direction</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="126"/>
        <source>Which way is up from the platform, in the scan's coordinates: the side the workpiece and the reference object P stand on (a direction; its length does not matter). Empty: from the data</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="130"/>
        <source>Fitting</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="131"/>
        <source>Random seed</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="132"/>
        <source>Refits</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="133"/>
        <source>Scanner position (mm)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="137"/>
        <source>Empty fields: automatic.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="145"/>
        <source>Stop the calibration; the document stays as it was</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="162"/>
        <source>Calibrating...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="165"/>
        <source>Needs the scan and both models</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="168"/>
        <source>Find where the workpiece is</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="170"/>
        <source>Could not calibrate: {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="172"/>
        <source>Calibrated in {:.1f} s</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="200"/>
        <source>Calibrate again</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="264"/>
        <source>Calibrating</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="265"/>
        <source>starting</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="266"/>
        <source>calibrating {} against {} and {} ...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="277"/>
        <source>Cancelling...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="344"/>
        <source>Calibration {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="353"/>
        <source>calibration not done: {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="354"/>
        <source>Not calibrated: {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="363"/>
        <source>calibration cancelled; the document is unchanged</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/calibrate.py" line="364"/>
        <source>Cancelled: the document is unchanged.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="22"/>
        <source>Robot</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="22"/>
        <source>3-axis machine</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="23"/>
        <source>5-axis machine</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="29"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="76"/>
        <source>Export</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="30"/>
        <source>Export: the program for the robot or the machine</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="31"/>
        <source>Write the calibrated toolpath as KUKA KRL, ABB RAPID, URScript, Fanuc LS, G-code or CSV, checked for the machine it is for</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="41"/>
        <source>The controller's language</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="45"/>
        <source>What the program is for: a robot (KRL, RAPID, URScript, Fanuc, CSV), or for G-code a 3-axis machine (the tool stays vertical) or a 5-axis machine with tool centre point control</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="55"/>
        <source>3-axis machine: how far W may tilt the tool from the machine's Z (the CLI's --vertical-tol)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="57"/>
        <source>5-axis machine: its two rotary axes (the CLI's --rotary)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="61"/>
        <source>Tilt allowed</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="62"/>
        <source>Rotary axes</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="63"/>
        <source>Format</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="64"/>
        <source>Machine</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="70"/>
        <source>The program file to write (replaced as a whole, never half written)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="72"/>
        <source>File</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="74"/>
        <source>Browse...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="74"/>
        <source>Choose the file</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="81"/>
        <source>Allow this tilt for the tool and export again</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="83"/>
        <source>Export for 5 axes</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="84"/>
        <source>Write G-code with rotary axes for a 5-axis machine</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="161"/>
        <source>Program</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="170"/>
        <source>written: {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="173"/>
        <source>Needs a calibration and the toolpath</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="174"/>
        <source>Write the program</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="199"/>
        <source>Export robot program</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="203"/>
        <source>Written: {} ({} for the {})</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="212"/>
        <source>This toolpath tilts the tool {:.2f} deg: a 3-axis machine cannot follow it. Export it for a 5-axis machine.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="215"/>
        <source>The part sits tilted: W turns the tool {:.3f} deg away from the machine's Z, more than the {:g} deg allowed for a 3-axis machine. Level the part (shim it) and calibrate again, allow {:g} deg if your tool can take it, or export for a 5-axis machine.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/export.py" line="221"/>
        <source>Allow {:g} deg</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/models.py" line="16"/>
        <source>Models: the workpiece and the reference object</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/models.py" line="17"/>
        <source>The workpiece model X-A in its own frame X (the toolpath's), and the reference model B-P placed where the reference object stands in the robot base frame B</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/models.py" line="19"/>
        <source>Workpiece model</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/models.py" line="20"/>
        <source>The workpiece as designed (X-A), in its own frame X: the frame the toolpath was computed in</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/models.py" line="22"/>
        <source>Reference model</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/models.py" line="23"/>
        <source>The fixed reference object (B-P), placed where it stands in the robot base frame B</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/models.py" line="35"/>
        <source>From a file...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/models.py" line="36"/>
        <source>STEP, IGES, BREP, STL, OBJ, OFF, PLY or a point file</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/models.py" line="39"/>
        <source>The workpiece model is used in its own frame, the toolpath's. The reference model must stand where the reference object stands for the robot.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/models.py" line="47"/>
        <source>Choose the {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/models.py" line="47"/>
        <source> and the </source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/models.py" line="48"/>
        <source>workpiece: {}, reference: {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/models.py" line="94"/>
        <source>Workpiece model (its own frame)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/models.py" line="95"/>
        <source>Reference model (robot frame)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="18"/>
        <source>Regions</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="19"/>
        <source>Regions: the workpiece and the reference object in the scan</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="20"/>
        <source>Which scan points are on the workpiece and which on the reference object: found with the models, or picked by hand</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="26"/>
        <source>Find them automatically</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="27"/>
        <source>Remove the platform, split the objects and match each model to them</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="30"/>
        <source>Pick: box</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="30"/>
        <source>Pick a region by dragging boxes in the 3D view</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="32"/>
        <source>Pick: lasso</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="32"/>
        <source>Pick a region by drawing polygons in the 3D view</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="34"/>
        <source>Clear the regions</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="35"/>
        <source>Forget both regions of the scan</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="36"/>
        <source>Orange: the workpiece. Blue: the reference object. Check them before calibrating; the calibration can also find them itself.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="54"/>
        <source>Import the scan first</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="56"/>
        <source>The regions no longer fit the scan: find or pick them again</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="60"/>
        <source>found by the calibration: workpiece {} points, reference {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="62"/>
        <source>Find the workpiece and the reference object in the scan</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="63"/>
        <source>found</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="63"/>
        <source>picked</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="64"/>
        <source>{}: workpiece {} points, reference {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/regions.py" line="122"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/scan.py" line="15"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/scan.py" line="84"/>
        <source>Scan</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="25"/>
        <source>OK: W can be used</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="26"/>
        <source>AMBIGUOUS: another pose fits almost as well</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="27"/>
        <source>FAILED: do not use W</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="28"/>
        <source>NOT CALIBRATED: the inputs could not be used</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="38"/>
        <source>Result</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="39"/>
        <source>Result: where the workpiece is, and can it be trusted</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="40"/>
        <source>The verdict, W = ^B X (the workpiece in the robot base frame), the checks and the uncertainty; accept it, or calibrate again</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="51"/>
        <source>Where the workpiece is</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="52"/>
        <source>W = ^B X = V^-1 U: the workpiece frame X in the robot base frame B</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="58"/>
        <source>Position</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="58"/>
        <source>W's translation, mm</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="59"/>
        <source>Rotation</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="59"/>
        <source>W's rotation as FreeCAD's placement shows it: an angle about an axis</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="62"/>
        <source>Angles Z-Y-Z</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="62"/>
        <source>The paper's Euler angles phi, theta, psi (Z-Y-Z)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="64"/>
        <source>Total turn</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="64"/>
        <source>The paper's Omega: the angle of W's rotation about its own axis, acos((trace R - 1) / 2)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="77"/>
        <source>Check</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="77"/>
        <source>Value</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="94"/>
        <source>The previous pose</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="95"/>
        <source>The next pose</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="96"/>
        <source>Poses that fit:</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="103"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="256"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="175"/>
        <source>Accept</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="103"/>
        <source>W is right: go on to the toolpath</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="106"/>
        <source>Redo</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="106"/>
        <source>Change the options or the regions and calibrate again</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="110"/>
        <source>Open the report</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="111"/>
        <source>Write the full report (HTML) and open it</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="113"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="281"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="278"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="294"/>
        <location filename="../../workcal_wb/gui/view_providers/calibration.py" line="101"/>
        <source>Deviation map</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="114"/>
        <source>Colour the workpiece's scan points by their distance to its model, against the tolerance</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="134"/>
        <source>Calibrate first</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="137"/>
        <source>OK, accepted</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="138"/>
        <source>OK: check it and accept it</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="146"/>
        <source>No calibration yet.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="165"/>
        <source>{} deg about ({}, {}, {})</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="174"/>
        <source>Accepted</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="207"/>
        <source>At the toolpath: off by up to {} mm (tolerance {} mm).</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="210"/>
        <source>No toolpath chosen yet. On the workpiece surface: off by up to {} mm (tolerance {} mm).</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="236"/>
        <source>Showing pose {} of {} of the {}{}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="237"/>
        <source> (the calibration's)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="265"/>
        <source>Calibration report</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="280"/>
        <source>Show the scan</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="297"/>
        <source>Workpiece model, placed</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/result.py" line="298"/>
        <source>Reference model, placed</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/scan.py" line="16"/>
        <source>Scan: the part and the reference object, seen at once</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/scan.py" line="17"/>
        <source>One 3D scan that sees both the workpiece and the fixed reference object (scanner frame S)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/scan.py" line="23"/>
        <source>Import a scan file...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/scan.py" line="24"/>
        <source>PLY, PCD, XYZ, ASC, PTS, CSV, E57, STL, OBJ or OFF; it becomes the scan of this document</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/scan.py" line="27"/>
        <source>Or use a point cloud of this document:</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/scan.py" line="28"/>
        <source>A point cloud or mesh already in the document</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/scan.py" line="29"/>
        <source>Choose the scan</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/scan.py" line="36"/>
        <source>Import the scan of the part and the reference object</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/scan.py" line="38"/>
        <source>{}: {} points</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/scan.py" line="45"/>
        <source>, read in {}</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="16"/>
        <source>Toolpath: the CAM toolpath, carried to where the part is</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="17"/>
        <source>The toolpath in the workpiece's own frame (X-m): a Path/CAM Job or a G-code file, carried into the robot base frame by W (B-m = W X-m)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="21"/>
        <source>The toolpath as the CAM system wrote it, in the workpiece model's frame. Chosen once; the export uses it too.</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="23"/>
        <source>A Path/CAM Job or operation of this document, or the G-code file chosen</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="28"/>
        <source>G-code file...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="29"/>
        <source>A G-code file (opens where the scan lies)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="31"/>
        <source>Show it in the robot frame</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="32"/>
        <source>Carry the toolpath into the robot base frame with the calibration's W and show it with the placed workpiece</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="55"/>
        <source>Choose the toolpath (CAM Job or G-code file)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="57"/>
        <source>{}: show it in the robot frame</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="58"/>
        <source>{}, shown in the robot frame</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="95"/>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="25"/>
        <source>Choose the toolpath</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="134"/>
        <source>Workpiece model: the toolpath's frame</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="137"/>
        <source>Toolpath in the robot frame</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/task_panels/steps/toolpath.py" line="138"/>
        <source>Workpiece, placed</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/view_providers/deviation_map.py" line="29"/>
        <source>Deviation from the model</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/view_providers/deviation_map.py" line="30"/>
        <source>green: within +/- {} mm</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/view_providers/deviation_map.py" line="32"/>
        <source>red: material added</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/view_providers/deviation_map.py" line="32"/>
        <source>blue: material removed</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/view_providers/deviation_map.py" line="33"/>
        <source>grey: no model near</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_AutoRegions</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="143"/>
        <source>Find regions automatically</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="144"/>
        <source>Find the workpiece and the reference object in the scan with their models (removes the platform, splits the objects and matches them); correct the result with the pick tools</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_Calibrate</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/calibrate.py" line="13"/>
        <source>Calibrate</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/calibrate.py" line="14"/>
        <source>Find where the workpiece is in the robot's base frame: match the workpiece and the reference object in the scan (W = V^-1 U)</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_ChooseModels</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/models.py" line="95"/>
        <source>Choose models...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/models.py" line="96"/>
        <source>Choose the workpiece model (X-A, in its own frame) and the reference model (B-P, in the robot base frame): Part shapes, meshes or point clouds from the document or from files</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_ClearRegions</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="154"/>
        <source>Clear regions</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="155"/>
        <source>Remove the workpiece and reference regions of the scan</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_DeviationMap</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="42"/>
        <source>Deviation map</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="43"/>
        <source>Colour the workpiece's scan points by their distance to its placed model: green within the tolerance, red where clay was added, blue where it was removed</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_ExportToolpath</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/toolpath.py" line="105"/>
        <source>Export robot program</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/toolpath.py" line="106"/>
        <source>Write the toolpath through the calibration as KUKA KRL, ABB RAPID, URScript, Fanuc LS, G-code or CSV, for a robot or a 3- or 5-axis machine</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_Guide</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/guide.py" line="33"/>
        <source>Guide...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/guide.py" line="34"/>
        <source>The steps of a calibration one after the other: scan, models, regions, calibrate, result, toolpath, export; the next one to do is highlighted</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_ImportScan</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="104"/>
        <source>Import scan...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/import_scan.py" line="105"/>
        <source>Read a 3D scan of the mounted workpiece and the reference object (PLY, PCD, XYZ, ASC, PTS, CSV, E57, STL, OBJ, OFF); it becomes the document's scan</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_PickBox</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="88"/>
        <source>Pick region (box)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="89"/>
        <source>Pick the workpiece or the reference region of the scan by dragging boxes in the 3D view (Shift adds, Ctrl subtracts)</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_PickLasso</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="101"/>
        <source>Pick region (lasso)</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/regions.py" line="102"/>
        <source>Pick the workpiece or the reference region of the scan by drawing polygons in the 3D view; right-click or Enter closes</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_Preferences</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/preferences.py" line="124"/>
        <source>Preferences...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/preferences.py" line="125"/>
        <source>Default units, tolerance, matching method and export format</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_Report</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="89"/>
        <source>Calibration report</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="90"/>
        <source>Write the report of the calibration (where the workpiece is, residuals, uncertainty, checks, deviation map) and open it</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_ShowInRobotFrame</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="53"/>
        <source>Show the workpiece model in the robot frame</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="54"/>
        <source>Show the workpiece model where the calibration puts it in the robot base frame (placed by W), beside the reference model</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_Studies</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="242"/>
        <source>Studies...</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/report.py" line="243"/>
        <source>Run one of the accuracy studies on a simulated scene and show its plot</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>WorkCal_TransformToolpath</name>
    <message>
        <location filename="../../workcal_wb/gui/commands/toolpath.py" line="81"/>
        <source>Calibrated toolpath</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/commands/toolpath.py" line="82"/>
        <source>Show the document's toolpath (its CAM Job or G-code file) carried from the workpiece's frame into the robot base frame by the calibration</source>
        <translation type="unfinished"></translation>
    </message>
</context>
<context>
    <name>Workbench</name>
    <message>
        <location filename="../../workcal_wb/gui/workbench.py" line="14"/>
        <source>WorkCal</source>
        <translation type="unfinished"></translation>
    </message>
    <message>
        <location filename="../../workcal_wb/gui/workbench.py" line="15"/>
        <source>Locate a freeform workpiece for a robot from one 3D scan and calibrate its toolpath</source>
        <translation type="unfinished"></translation>
    </message>
</context>
</TS>
