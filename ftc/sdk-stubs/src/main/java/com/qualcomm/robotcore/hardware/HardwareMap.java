// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.robotcore.hardware;

import android.content.Context;
import com.qualcomm.robotcore.eventloop.opmode.OpModeManagerNotifier;
import java.util.ArrayList;
import java.util.Iterator;
import java.util.LinkedHashMap;
import java.util.List;
import java.util.Map;

/** Stub of the robot's configured devices by name; tests fill it with put(). */
public class HardwareMap implements Iterable<HardwareDevice> {
    public DeviceMapping<DcMotor> dcMotor = new DeviceMapping<DcMotor>(DcMotor.class);
    public DeviceMapping<DigitalChannel> digitalChannel = new DeviceMapping<DigitalChannel>(DigitalChannel.class);
    public DeviceMapping<VoltageSensor> voltageSensor = new DeviceMapping<VoltageSensor>(VoltageSensor.class);

    public final Context appContext;
    private final Map<String, List<HardwareDevice>> byName = new LinkedHashMap<String, List<HardwareDevice>>();

    public HardwareMap(Context appContext, OpModeManagerNotifier notifier) {
        this.appContext = appContext;
    }

    public <T> T get(Class<? extends T> classOrInterface, String deviceName) {
        T result = tryGet(classOrInterface, deviceName);
        if (result == null) {
            throw new IllegalArgumentException(String.format("Unable to find a hardware device with name \"%s\" and type %s",
                    deviceName, classOrInterface.getSimpleName()));
        }
        return result;
    }

    public <T> T tryGet(Class<? extends T> classOrInterface, String deviceName) {
        List<HardwareDevice> list = byName.get(deviceName.trim());
        if (list != null) {
            for (HardwareDevice device : list) {
                if (classOrInterface.isInstance(device)) {
                    @SuppressWarnings("unchecked")
                    T typed = (T) device;
                    return typed;
                }
            }
        }
        return null;
    }

    public HardwareDevice get(String deviceName) {
        return get(HardwareDevice.class, deviceName);
    }

    public <T> List<T> getAll(Class<? extends T> classOrInterface) {
        List<T> result = new ArrayList<T>();
        for (HardwareDevice device : this) {
            if (classOrInterface.isInstance(device)) {
                @SuppressWarnings("unchecked")
                T typed = (T) device;
                result.add(typed);
            }
        }
        return result;
    }

    public void put(String deviceName, HardwareDevice device) {
        String name = deviceName.trim();
        List<HardwareDevice> list = byName.get(name);
        if (list == null) {
            list = new ArrayList<HardwareDevice>();
            byName.put(name, list);
        }
        list.add(device);
        if (device instanceof DcMotor) {
            dcMotor.put(name, (DcMotor) device);
        }
        if (device instanceof DigitalChannel) {
            digitalChannel.put(name, (DigitalChannel) device);
        }
        if (device instanceof VoltageSensor) {
            voltageSensor.put(name, (VoltageSensor) device);
        }
    }

    public int size() {
        int n = 0;
        for (List<HardwareDevice> list : byName.values()) {
            n += list.size();
        }
        return n;
    }

    @Override
    public Iterator<HardwareDevice> iterator() {
        List<HardwareDevice> all = new ArrayList<HardwareDevice>();
        for (List<HardwareDevice> list : byName.values()) {
            all.addAll(list);
        }
        return all.iterator();
    }

    /** Devices of one type by name, as the SDK's hardwareMap.dcMotor etc. */
    public class DeviceMapping<DEVICE_TYPE extends HardwareDevice> implements Iterable<DEVICE_TYPE> {
        private final Class<DEVICE_TYPE> deviceTypeClass;
        private final Map<String, DEVICE_TYPE> map = new LinkedHashMap<String, DEVICE_TYPE>();

        public DeviceMapping(Class<DEVICE_TYPE> deviceTypeClass) {
            this.deviceTypeClass = deviceTypeClass;
        }

        public Class<DEVICE_TYPE> getDeviceTypeClass() {
            return deviceTypeClass;
        }

        public DEVICE_TYPE get(String deviceName) {
            DEVICE_TYPE device = map.get(deviceName.trim());
            if (device == null) {
                throw new IllegalArgumentException(String.format("Unable to find a hardware device with the name \"%s\"", deviceName));
            }
            return device;
        }

        public void put(String deviceName, DEVICE_TYPE device) {
            map.put(deviceName.trim(), device);
        }

        public boolean contains(String deviceName) {
            return map.containsKey(deviceName.trim());
        }

        @Override
        public Iterator<DEVICE_TYPE> iterator() {
            return map.values().iterator();
        }
    }
}
